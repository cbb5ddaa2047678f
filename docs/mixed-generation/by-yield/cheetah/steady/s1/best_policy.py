# colmo best policy for cheetah: training score 257.89, held-out 227.83 after 247 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = np.zeros(6) + np.array([0.1133, -0.8408, -0.7993, 0.2409, -0.4356, -0.8496]) * obs[0]
    # coverage: if `np.abs(obs[6]) < 46.25`: true 100% of 110,000 tests (always true)
    if np.abs(obs[6]) < 46.25:
        return action + np.array([12.96, 1.779, 40.5, 22.23, -0.3453, -65.53]) * (-24.35 * obs[3] - -18.15 * obs[5])
    # coverage: if `obs[12] > -1.292`: never reached
    elif obs[12] > -1.292:
        return action + np.array([-57.67, -31.2, -131.3, -0.7614, 26.25, -0.9822]) * obs[5] ** 2 - -3.121 * obs[1]
    # coverage: if `obs[8] < 0.5399`: never reached
    elif obs[8] < 0.5399:
        return -0.07771 * obs[7]
    else:
        return 0.1782 * action