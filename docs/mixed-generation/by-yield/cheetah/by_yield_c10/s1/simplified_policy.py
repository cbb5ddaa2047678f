# colmo: the best policy of cheetah simplified: training score 288.62, held-out 263.50
import numpy as np

def policy(obs):
    if obs[10] > -3.246 - 10.19 * obs[7] ** 2:
        action = 0.0
    else:
        action = 4.278
    return np.tanh(action + -0.02755 * obs[3]) + np.array([10.41, 0.0, 2.992, -0.1103, -14.28, -1.107]) * obs[7]
