# tuned by colmo-optimize (gfo=oneplusone): training score 151.18, held-out 150.33
import numpy as np

def policy(obs):
    action = 0.01618 * obs[21] + np.array([0.9068, 2.143 * obs[13], 0.1301, -0.3416, -0.2215, -0.5216, 0.1488, 1.006, 0.1633, 0.142, -0.4444, 0.9162]) * obs[3] ** 2
    action_b = 0.01441 * obs[21] + np.array([0.8376, -0.3028, 0.126, -0.3413, -0.2555, -0.5609, 0.1198, 0.8416, 0.1397, 0.1515, -0.5425, 0.8151]) * obs[3] ** 2
    return 0.5073 * action + 0.4953 * action_b
