# colmo best policy for a1: training score 165.01, held-out 144.38 after 130 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `obs[14] < 1.044`: true 50% of 110,000 tests
    if obs[14] < 1.044:
        action = np.zeros(12)
    else:
        action = np.zeros(12) + 1.928 * obs[6]
    return action + np.array([7.436, 0.1174, -10.83, 6.621, -0.01459, -0.4099, 0.6895, -0.09851 + 0.8977 * 0.9455 ** 2, -2.466, 0.7741, -1.552, 0.125]) * obs[20] * obs[2]