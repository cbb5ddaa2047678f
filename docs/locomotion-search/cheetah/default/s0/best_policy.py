# colmo best policy for cheetah: training score 265.91, held-out 238.05 after 319 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = np.zeros(6)
    # coverage: if `obs[8] > -0.09632`: true 92% of 110,000 tests
    if obs[8] > -0.09632:
        return action * ((5.053 * obs[12] - 2.648 * obs[11] - 0.1662 * np.tanh(obs[5])) * obs[13]) + np.array([1.394, 0.3802, 3.171, -0.1034, -2.738, 0.2273]) * np.tanh(np.sign(obs[16]))
    else:
        return action * (np.array([0.2739, -0.06865, 0.3868, 0.2007, -0.1408, 0.1702]) * obs[13]) + np.array([0.2459, -0.542, -0.8909, 0.7231, -0.1735, 0.5673]) * np.sign(obs[16]) - 1.254 * obs[15] + np.array([-0.5136, -0.8318, -0.4047, -0.1001, -0.4353, -0.8073]) * obs[16]