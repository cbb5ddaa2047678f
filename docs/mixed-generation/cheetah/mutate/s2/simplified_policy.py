# colmo: the best policy of cheetah simplified: training score 202.18, held-out 186.07
import numpy as np

def policy(obs):
    action = np.zeros(6) - -2.197 * obs[13] ** 2 * obs[9]
    return action + 7.479 * (-3.226 * obs[8] + 2.44 * obs[16])
