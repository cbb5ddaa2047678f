# colmo best policy for pendulum: training score 209.10, held-out 189.87 after 48 samples
import numpy as np

def policy(obs):
    theta = obs[0]
    angular_velocity = obs[2]
    torque = np.cos(theta) * angular_velocity
    action = torque / 0.1409
    return np.clip(action, -0.6953, 0.7791)