# colmo best policy for pendulum: training score 187.90, held-out 189.99 after 48 samples
import numpy as np

def policy(obs):
    theta = np.arctan2(obs[1], obs[0])
    angular_velocity = obs[2]
    if angular_velocity > 0.1263:
        action = 0.9868 * 1.308
    elif angular_velocity < -0.1188:
        action = -2.708 * 1.136
    else:
        action = 0.05386
    return np.clip(action, -0.7503, 1.155)