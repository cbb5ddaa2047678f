# colmo: the best policy of cheetah simplified: training score 251.74, held-out 244.23
import numpy as np

def policy(obs):
    action = 1.09 * obs[9]
    return np.sin(action) + np.array([37.48, 1.642, 8.868, 7.033, 62.84, 341.6]) * obs[1]
