# colmo best policy for cheetah: training score 201.53, held-out 180.88 after 335 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `obs[3] < -0.9524`: true 0.038% of 110,000 tests
    if obs[3] < -0.9524:
        # coverage: if `obs[3] < -0.7832`: true 100% of 42 tests (always true)
        if obs[3] < -0.7832:
            action = np.zeros(6)
        else:
            action = np.zeros(6) - -2.959 * (-6.732 * obs[14] - obs[11]) ** 2 * obs[9]
        action = np.zeros(6)
    else:
        action = np.zeros(6) - -2.197 * obs[13] ** 2 * obs[9]
    return action + 7.48 * (-3.225 * obs[8] + 2.439 * obs[16])