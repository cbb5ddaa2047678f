# colmo: the best policy of cheetah simplified: training score 257.89, held-out 227.83
import numpy as np

def policy(obs):
    action = np.array([0.1133, -0.8408, -0.7993, 0.2409, -0.4356, -0.8496]) * obs[0]
    return action + np.array([12.96, 1.779, 40.5, 22.23, -0.3453, -65.53]) * (-24.35 * obs[3] - -18.15 * obs[5])
