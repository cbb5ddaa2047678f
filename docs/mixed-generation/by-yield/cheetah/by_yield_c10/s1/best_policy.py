# colmo best policy for cheetah: training score 289.60, held-out 257.98 after 607 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `obs[10] > -3.246 - 10.19 * obs[7] ** 2`: true 98% of 110,000 tests
    if obs[10] > -3.246 - 10.19 * obs[7] ** 2:
        action = np.zeros(6)
    else:
        action = np.zeros(6)
        action = 4.278 * np.arctan2(obs[11], obs[10])
    return np.tanh(action + -0.02755 * obs[3]) + np.array([10.41, -(1.035 * obs[2]), 2.992, -0.1103, -14.28, -1.107]) * obs[7]