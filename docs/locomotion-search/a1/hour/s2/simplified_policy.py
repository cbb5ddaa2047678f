# colmo: the best policy of a1 simplified: training score 150.48, held-out 151.40
import numpy as np

def policy(obs):
    action = 0.0162 * obs[21] + np.array([0.9069, 2.143 * obs[13], 0.13, -0.3416, -0.2213, -0.5207, 0.1489, 1.005, 0.1634, 0.1417, -0.4442, 0.9165]) * obs[3] ** 2
    action_b = 0.0146 * obs[21] + np.array([0.8374, -0.303, 0.1259, -0.3418, -0.2553, -0.5607, 0.1199, 0.8434, 0.1395, 0.1517, -0.5424, 0.8156]) * obs[3] ** 2
    return 0.5068 * action + 0.4948 * action_b
