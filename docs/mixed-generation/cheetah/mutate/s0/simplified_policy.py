# colmo: the best policy of cheetah simplified: training score 236.78, held-out 221.38
import numpy as np

def policy(obs):
    action = np.zeros(6) - (-0.3877 * obs[11] - 31.36 * obs[1] + 3.743 * obs[5]) + 4.786 * obs[6]
    return action
