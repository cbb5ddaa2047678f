# colmo best policy for cheetah: training score 235.80, held-out 226.84 after 281 samples
# decided by the code: `np.abs(obs[12]) > -0.1679` is always true (`np.abs(obs[12])` is in [0, inf])
# decided by the code: `np.abs(obs[12]) < -0.3674` is never true (`np.abs(obs[12])` is in [0, inf])
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `np.abs(obs[12]) > -0.1679`: true 100% of 110,000 tests (always true)
    if np.abs(obs[12]) > -0.1679:
        action = np.zeros(6)
    else:
        action = 0.09642 - obs[7] - 2.644 * np.tanh(obs[1]) + 0.01622 * obs[11]
    # coverage: if `np.abs(obs[12]) < -0.3674`: true 0% of 110,000 tests (never true)
    if np.abs(obs[12]) < -0.3674:
        action_b = np.zeros(6) + 0.6161 * obs[11] * obs[10]
    else:
        action_b = -0.1139 * obs[7] + -0.09473 * obs[11]
        action = 0.03055 - obs[7] - 12.87 * np.tanh(obs[1]) + 0.0432 * obs[11]
    # coverage: conditional `obs[10] > -0.2134`: true 54% of 110,000 tests
    return obs[7] + np.array([11.06, 1.962, -0.3064 - 43.83 * obs[4] - -(0.01304 * obs[9] - 0.203 * obs[10] - 0.6077 * obs[16]) * obs[2], 0.1153, 4.246 * obs[11], -10.35]) * np.arctan2(np.sign(obs[14]), obs[2]) if obs[10] > -0.2134 else action_b + np.array([5.242, 1.687, -0.1445 - 2.056 * obs[4] - -0.6753 * obs[2], 0.01183, 0.03968, -7.206]) * np.arctan2(np.sign(obs[14]), np.cos(obs[2]))