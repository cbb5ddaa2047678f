# colmo best policy for cheetah: training score 224.46, held-out 165.12 after 245 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = np.zeros(6) + np.array([0.6355, 0.08733, 0.1878, 0.3038, -0.1231, -0.1384]) * obs[11]
    action_b = np.zeros(6) + np.array([2.792, -0.2427, 0.5944, -0.1891, -0.06117, 0.1132]) * obs[11]
    action_b = np.zeros(6) + np.array([1.458, -0.0003649, 0.4044, 0.5276, 0.1681, -0.03445]) * obs[11] + np.array([0.4329, -0.09416, -0.4969, 0.4798, 0.08459, -0.9423]) * obs[0]
    # coverage: conditional `obs[4] < 0.2304`: true 61% of 110,000 tests
    return 0.7728 * (action + np.array([0.06466, -0.06567, -0.07158, -0.5326, 0.04413, 0.2638]) * obs[3] + np.array([0.05759, 0.107, 0.2476, -0.9792, 0.1928, -0.08851]) * obs[6] * obs[10] + np.array([0.2567, 0.418, -0.4556, 0.01435, 0.5318, -0.2093 * obs[4] - 0.1018 * obs[11]]) * np.sin(obs[10]) if obs[4] < 0.2304 else action_b + np.array([0.05972, 0.1911, -0.01627, 0.2254, 0.2849, 0.1372]) * obs[3] + (np.array([0.1591, 0.1751, 0.206, 0.4006, -(1.505 - 1.971 * obs[12] * obs[3]), -0.3791]) + obs[6]) * obs[10]) + 0.1241 * (action_b + np.array([-0.01702, -0.06888, 0.03963, 0.3125, 0.08186, -0.114]) * obs[3] + np.array([0.02588, 0.01845, 0.1761, -0.6788, -2.102, 0.009498]) * obs[6] * obs[10])