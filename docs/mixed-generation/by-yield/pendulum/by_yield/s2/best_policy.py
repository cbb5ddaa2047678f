# colmo best policy for pendulum: training score 789.10, held-out 839.29 after 494 samples
# decided by the code: `obs[1] < 2.118` is always true (`obs[1]` is in [-1, 1])
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `obs[0] < -0.1043`: true 10% of 110,000 tests
    if obs[0] < -0.1043:
        # coverage: `np.clip(-0.5746 / obs[1], -0.7353, -6.422)`: changed 100% of 11,402 values (3% raised, 97% lowered): always at a limit
        # coverage: `-0.5746 / obs[1]`: divisor never 0 in 11,402 values
        action_b = 9.673 * obs[2] - obs[1] + np.clip(-0.5746 / obs[1], -0.7353, -6.422) + -(-0.1162 + 0.1928 * obs[1])
    # coverage: if `obs[1] < 2.118`: true 100% of 98,598 tests (always true)
    elif obs[1] < 2.118:
        # coverage: if `obs[1] ** 2 > 0.3697`: true 6% of 98,598 tests
        if obs[1] ** 2 > 0.3697:
            action_b = 1.182 * obs[0] - -0.03254 * obs[1]
        else:
            action_b = -0.05072 * obs[0] - -0.1599 * obs[1] - 0.1463 * np.abs(obs[2])
    else:
        action_b = -0.05296 * obs[0] - 0.9217 * obs[1] - 0.5721 * obs[0]
    # coverage: if `obs[0] > -0.1026`: true 90% of 110,000 tests
    if obs[0] > -0.1026:
        # coverage: `np.clip(-0.01431 / obs[1], 0.01002, -1.11 - np.sin(obs[1]))`: changed 100% of 98,582 values (0.087% raised, 100% lowered): always at a limit
        # coverage: `-0.01431 / obs[1]`: divisor never 0 in 98,582 values
        action = 26.67 * obs[2] - obs[1] + np.clip(-0.01431 / obs[1], 0.01002, -1.11 - np.sin(obs[1])) + -0.003818 * np.sin(obs[1])
    else:
        action = -0.09112 * obs[0] - 0.06016 * -0.2399
    # coverage: if `obs[0] < 0.7568`: true 16% of 110,000 tests
    if obs[0] < 0.7568:
        # coverage: `np.clip(0.123 / obs[1], -0.002252, 4.055)`: changed 54% of 17,175 values (54% raised, 0.75% lowered)
        # coverage: `0.123 / obs[1]`: divisor never 0 in 17,175 values
        action_b = 17.71 * obs[2] - obs[1] + np.clip(0.123 / obs[1], -0.002252, 4.055) - -0.007157 * np.sin(obs[1])
    else:
        action_b = np.abs(-0.2304 * obs[0]) - 3.02 * obs[1]
    # coverage: if `obs[2] > -5.506`: true 98% of 110,000 tests
    if obs[2] > -5.506:
        return 0.1903 * (action + 0.1713 * obs[2] * obs[1] - -2.135 * np.cos(obs[2])) + 4.88 * (action_b - (0.3191 * obs[1] + 1.765 * obs[2]))
    # coverage: if `np.abs(np.arctan2(obs[1], obs[0])) > 0.6135`: true 100% of 2,499 tests (always true)
    elif np.abs(np.arctan2(obs[1], obs[0])) > 0.6135:
        return 0.06704 * (action + 0.6493 * obs[2] * obs[1] - -0.006419 * np.cos(obs[2])) + 0.3652 * (action_b - (1.771 * obs[1] + 0.1441 * obs[2])) - 1.366 * obs[1]
    else:
        return -0.5684 * obs[0] * obs[1]