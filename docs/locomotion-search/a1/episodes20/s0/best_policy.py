# colmo best policy for a1: training score 132.18, held-out 131.19 after 110 samples
# branches counted over 120 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `obs[7] * obs[19] < 3.258`: true 85% of 120,000 tests
    if obs[7] * obs[19] < 3.258:
        action = np.zeros(12) + np.array([1.075, 0.1265, -0.02818, 0.6952, 2.194, 0.3908, 0.1145 - obs[2], -0.1806, 0.1994, 0.1131, 0.03735, 0.1907]) * np.sign(obs[13])
    else:
        action = np.zeros(12) + np.array([4.499, -1.437, 0.07398, np.sign(-0.1239), 6.414, 0.1925, 0.7645 - -0.1611 * obs[2] * obs[24], -1.839, 1.128, 0.6492, 0.09763, 0.02717]) * np.sign(obs[13]) - 19.02 * obs[22] * obs[16]
    # coverage: if `obs[7] * obs[19] > -0.2355`: true 50% of 120,000 tests
    if obs[7] * obs[19] > -0.2355:
        # coverage: if `np.abs(obs[13]) < 0.4151`: true 5% of 59,498 tests
        if np.abs(obs[13]) < 0.4151:
            # coverage: if `obs[24] > 1.459`: true 0% of 2,759 tests (never true)
            if obs[24] > 1.459:
                action_b = np.zeros(12) + np.array([2.01, -0.5806, -0.005337, -0.05366, 3.464, 0.4443, -0.06258 - -0.3227 * obs[2] * obs[24], 0.02483, -1.319, 0.6621, 0.01, 0.004472]) * np.sign(obs[13])
            else:
                action_b = -5.768 * obs[11] - 0.177 * obs[8]
        else:
            action_b = 0.2059 * obs[7] + 0.5178 * obs[26]
    else:
        action_b = np.zeros(12) + np.array([4.138, -1.957, -0.04732, -0.02068, 2.245, -0.1313, 0.1305 - -0.3225 * obs[2] * obs[24], -0.4514, 0.8271, 0.267, 0.1434, -0.3222]) * np.sign(obs[13]) - 28.75 * obs[22] * obs[16]
    action_b = np.zeros(12) - (0.1147 + obs[26])
    # coverage: conditional `np.abs(np.abs(obs[20])) < 0.2988`: true 27% of 120,000 tests
    # coverage: conditional `np.abs(obs[11] * obs[1]) > 1.174`: true 4% of 87,548 tests
    return action if np.abs(np.abs(obs[20])) < 0.2988 else action_b if np.abs(obs[11] * obs[1]) > 1.174 else action_b