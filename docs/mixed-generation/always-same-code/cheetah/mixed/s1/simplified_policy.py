# colmo: the best policy of cheetah simplified: training score 249.18, held-out 250.19
import numpy as np

def policy(obs):
    action = -4.579 + np.sin(obs[6])
    return action + (18.32 - 21.22 * (obs[16] - -0.06562 * np.arctan2(obs[3], obs[10]) + 1.72 * obs[1])) * np.arctan2(obs[2], np.abs(obs[8])) + np.array([1.139, -1.349, 1.458, 0.1433, -0.555, 0.3723]) * obs[11]
