# colmo best policy for quadruped: training score 101.55, held-out 99.98 after 56 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `obs[21] * obs[55] < -1.364`: true 23% of 110,000 tests
    if obs[21] * obs[55] < -1.364:
        action = np.zeros(12) + np.array([0.3813, -0.06957, -0.2562, 0.01124, -1.305, 0.1082, -0.2268 - -0.06145 * obs[8] * obs[71], -0.3157, 0.3667, 1.067, 0.05409, -0.03003]) * np.sign(obs[37])
    else:
        action = np.zeros(12) + np.array([0.02983, 0.6224, 0.07671, 0.1723, 0.7814, 0.1676, 0.005957 - 0.1924 * obs[8] * obs[71], -0.8769, 0.143, 0.2917, 0.2132, 0.1529]) * np.sign(obs[37]) - 10.02 * obs[65] * obs[48]
    action = np.zeros(12) + np.array([4.83, 0.7298, -0.6589, 2.131, 2.605, 0.2379, -0.3679, 0.9213, 0.9831, -0.2615, -0.05928 + -1.353 * np.abs(obs[53]), -0.5284]) * np.arctan2(obs[8], obs[63])
    return action