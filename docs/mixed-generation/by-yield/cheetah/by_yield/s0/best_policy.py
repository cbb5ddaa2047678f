# colmo best policy for cheetah: training score 260.94, held-out 234.90 after 179 samples
# decided by the code: `np.abs(obs[11] ** 2) > -0.07782` is always true (`np.abs(obs[11] ** 2)` is in [0, inf])
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `obs[4] > -0.4374`: true 84% of 110,000 tests
    if obs[4] > -0.4374:
        action_b = np.zeros(6) - 1.522 * obs[3]
    else:
        action_b = np.zeros(6) - 1.95 * obs[3] + 0.03685 * np.cos(obs[5])
    action = -0.5816 * obs[1] + 0.1111 * obs[9] - 4.351 * obs[3] + np.array([9.618, -0.06355, 1.005, obs[16], -1.885, 11.96]) * obs[16]
    action_b = 6.609 * np.arctan2(obs[11], obs[12]) + np.array([1.525, -0.3778, np.cos(-0.7689), 0.1139, -0.3556, 0.02407]) * obs[4]
    action_b = -2.965 * obs[7] + -0.5204 * obs[15] + np.array([0.1439, -0.1277, -3.628, obs[16], 0.2877, -6.929]) * obs[16]
    # coverage: conditional `np.abs(obs[11] ** 2) > -0.07782`: true 100% of 110,000 tests (always true)
    return 1.899 * action + 1.663 * (0.3931 - action_b + 1.142 * action_b if np.abs(obs[11] ** 2) > -0.07782 else action_b)