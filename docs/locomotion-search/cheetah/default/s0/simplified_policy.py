# colmo: the best policy of cheetah simplified: training score 265.91, held-out 238.05
import numpy as np

def policy(obs):
    if obs[8] > -0.09632:
        return np.array([1.394, 0.3802, 3.171, -0.1034, -2.738, 0.2273]) * np.tanh(np.sign(obs[16]))
    else:
        return np.array([0.2459, -0.542, -0.8909, 0.7231, -0.1735, 0.5673]) * np.sign(obs[16]) - 1.254 * obs[15] + np.array([-0.5136, -0.8318, -0.4047, -0.1001, -0.4353, -0.8073]) * obs[16]
