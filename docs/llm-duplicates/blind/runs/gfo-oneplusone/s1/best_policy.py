# colmo best policy for pendulum: training score 262.70, held-out 89.72 after 48 samples
import numpy as np

def policy(obs):
    theta = obs[0]
    angular_velocity = obs[2]
    if theta < 0.7259 or angular_velocity < 0.2555:
        action = 1.103
    else:
        action = -1.286
    return np.clip(action, -0.9939, 1.516)