# colmo best policy for pendulum: training score 21.40, held-out 67.40 after 25 samples
import numpy as np

def policy(obs):
    if np.abs(obs[1] ** 2) > 1.13:
        action = 0.0
    else:
        action = 0.0 - 5.65 * np.abs(obs[1])
    return action