# colmo: the best policy of quadruped simplified: training score 20.99, held-out 20.99
import numpy as np

def policy(obs):
    action = 10.63 * (obs[21] ** 2 + 0.6771 * np.sin(obs[18]) * np.arctan2(obs[21], obs[27]))
    action_b = np.zeros(12) - 8.982 * (-16.98 * obs[53] - -1.288 * obs[29])
    return 0.787 * action + -2.846 * action_b
