# colmo best policy for pendulum: training score 219.50, held-out 228.88 after 48 samples
import numpy as np

def policy(obs):
    angle = np.arccos(obs[0])
    angular_velocity = obs[2]
    if abs(angle - np.pi / 1.102) > 2.086:
        return 0.8032 * np.cos(obs[0])
    else:
        angular_velocity_change = obs[2]
        torque = 0.1745 * np.cos(obs[0]) + 0.3667 * angular_velocity_change
        torque = np.clip(torque, -0.9399, 0.8327)
        return torque