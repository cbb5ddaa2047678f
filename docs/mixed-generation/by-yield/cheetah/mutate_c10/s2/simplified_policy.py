# colmo: the best policy of cheetah simplified: training score 200.40, held-out 175.71
import numpy as np

def policy(obs):
    action = np.array([0.01177, -0.2343, -3.045, -3.593, 6.472, -1.715]) * obs[12] ** 2 - 0.3057 * np.arctan2(obs[16], obs[2]) - 0.3403 * obs[4]
    return action + 4.462 * obs[9]
