# colmo: the best policy of cheetah simplified: training score 227.41, held-out 138.66
import numpy as np

def policy(obs):
    action = -((10.15 * obs[3] - -0.1998 * obs[7]) * np.arctan2(obs[1], obs[3])) - 2.243 * obs[6] ** 2 - -2.209 * np.arctan2(obs[14], obs[16])
    action_b = np.zeros(6) - (13.9 * obs[3] - -0.2158 * obs[7]) * np.arctan2(obs[1], obs[3]) - (-1.188 - 0.1122 * np.abs(obs[12])) * obs[6] ** 2 - -3.738 * np.arctan2(obs[14], obs[16])
    return 0.4715 * action + 0.7817 * action_b
