# colmo best policy for pendulum: training score 216.90, held-out 189.59 after 48 samples
import numpy as np

def policy(obs):
    torque = 1.16
    angle = np.abs(obs[0])
    angular_velocity = obs[2]
    action = np.clip(angle * torque + angular_velocity * torque, -0.8738, 0.7051)
    return action