# colmo best policy for pendulum: training score 221.60, held-out 182.04 after 200 samples
import numpy as np

def policy(obs):
    theta = obs[0]
    angular_velocity = obs[2]
    torque = 3.202 * np.cos(theta) - 0.1307 * np.sin(theta) + 4.247 * angular_velocity + 1.434
    torque = np.clip(torque, -0.885, 0.6384)
    return torque