# colmo best policy for cheetah: training score 277.65, held-out 273.61 after 259 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `np.abs(obs[16]) > 0.1015`: true 99% of 110,000 tests
    if np.abs(obs[16]) > 0.1015:
        action = np.zeros(6) + np.array([0.1899, -0.0596 + -0.03925 * obs[11], 0.4975, -0.129, -25.56, -0.7963]) * np.arctan2(obs[5], obs[14]) + np.array([0.09204, -0.1036, 0.2608, -0.8801, -0.758, -0.3018 + -0.04862 * obs[5]]) * obs[7]
    # coverage: if `np.abs(obs[7]) > 0.09678`: true 74% of 1,342 tests
    elif np.abs(obs[7]) > 0.09678:
        action = np.zeros(6) + np.array([0.01143, 0.01984 + -0.0374 * obs[11], 0.3258, -0.145, -37.4, -1.25]) * np.arctan2(obs[5], obs[14]) + np.array([0.1585, -0.06081, 0.2754, -1.084, -0.903, -0.1155 + -0.01159 * obs[5]]) * obs[7] - 3.555 * np.sign(obs[13])
    else:
        action = np.zeros(6) + np.array([0.1404, -0.05925 + 0.01453 * obs[11], 0.4495, -0.07172, -44.56, -6.065]) * np.arctan2(obs[5], obs[14]) + np.array([0.08568, -0.1813, 0.1476 - 4.871 * np.sin(obs[4]), -0.07668, -0.743, -0.09449 + -0.07661 * obs[5]]) * obs[7] - 1.994 * np.sign(obs[13]) - 0.2032 * np.sin(obs[13])
    return action + np.array([-0.068, 0.2022, 0.1174, 7.422, 0.2798, -0.09979]) * (obs[6] - -0.5454 * obs[6])