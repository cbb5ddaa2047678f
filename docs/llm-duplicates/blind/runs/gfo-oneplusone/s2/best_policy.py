# colmo best policy for pendulum: training score 186.50, held-out 186.15 after 48 samples
import numpy as np

def policy(obs):
    theta = np.arctan2(obs[1], obs[0])
    angular_velocity = obs[2]
    if angular_velocity > 0.05026:
        action = 0.8944
    elif angular_velocity < -0.1399:
        action = -2.186
    else:
        action = 0.05946 + angular_velocity
    return np.clip(action, -1.489, 1.419)