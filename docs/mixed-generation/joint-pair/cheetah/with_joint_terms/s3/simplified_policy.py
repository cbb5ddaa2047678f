# colmo: the best policy of cheetah simplified: training score 215.95, held-out 190.92
import numpy as np

def policy(obs):
    action = 0.4368 * obs[8] + 3.022 * obs[2]
    return action - np.array([31.07, 4.037, 31.17, -24.59, 13.84, -1.0]) * obs[3]
