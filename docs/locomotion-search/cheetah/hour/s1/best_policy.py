# colmo best policy for cheetah: training score 327.01, held-out 311.32 after 506 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `np.abs(obs[9]) < 0.2087`: true 25% of 110,000 tests
    if np.abs(obs[9]) < 0.2087:
        action = 0.5708 * np.tanh(obs[7]) + (np.array([-0.05056, -(0.2427 - 1.23 * obs[0] ** 2), 0.4775, -2.209, -0.6271, 0.07864]) - 0.1063 * obs[4] - obs[7] + obs[9])
    else:
        action = 0.5961 * np.tanh(obs[7]) + (np.array([-0.05153, -(0.2757 - 1.17 * obs[0] ** 2), 0.4451, -2.327, -0.641, 0.07192]) - 0.09975 * obs[4] - obs[7] + obs[9]) - 0.1284 * np.arctan2(obs[6], obs[0])
    action = np.zeros(6) - 5.98 * np.tanh(obs[0])
    action_b = 4.595 * np.tanh(obs[7]) + np.array([-0.1316, -0.304, 0.5251, -1.534, -0.1453, 0.1894]) * obs[7] * obs[9]
    action_b = np.zeros(6)
    return 0.5759 * (action + np.array([0.08097, -0.1523 * obs[10], -1.984, 0.3227, -0.6301, -0.6567]) * np.sign(obs[2]) + np.array([0.6309, -0.1661, -0.5556, 0.6942, -0.104, -2.865]) * np.arctan2(obs[7], obs[11])) + 0.7043 * (action_b + np.array([-0.09175, -0.07468, -0.7754, 0.1011, -0.7262, -1.324]) * np.sign(obs[2]) + np.array([0.7123, -0.2407, -0.253, 0.6184, -0.2862 + 0.133 * obs[3], -1.08]) * np.arctan2(obs[7], obs[11]))