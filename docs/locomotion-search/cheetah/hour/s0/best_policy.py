# colmo best policy for cheetah: training score 325.75, held-out 309.65 after 588 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = np.zeros(6) + -0.1227 * np.arctan2(obs[0], obs[9])
    action = np.zeros(6) + np.array([-0.3246, 0.1958, 3.157, 0.9213, -0.1868, 0.0998]) * obs[9] * obs[0] + np.array([0.2561, 0.02989 * np.abs(obs[0]), 0.06303, 0.002515, 0.907, -0.4391]) * np.sign(obs[10])
    action = np.zeros(6) + np.array([-0.1736, -0.1821, 1.308, -0.1484, -0.1357, 1.116]) * obs[9] * obs[0]
    action_b = np.zeros(6)
    action_b = np.zeros(6) + -0.296 * np.arctan2(obs[0], obs[9])
    action_b = np.zeros(6) + np.array([-2.081, 0.1253, 1.142, 0.3205, -0.2179, 0.2435]) * obs[9] * obs[0] + np.array([0.09256, 0.2548, 0.1289, 0.114, 0.172, -0.323]) * np.sign(obs[10])
    action_b_b = np.zeros(6)
    action_b_b = np.zeros(6) + -0.1821 * np.arctan2(obs[0], obs[9])
    action_b_b = np.zeros(6) + np.array([-0.6764, 0.05324, 2.616, 0.8793, -0.256, 0.4244]) * obs[9] * obs[0] + np.array([0.2493, 0.2868 * np.abs(obs[0]), 0.1631, 0.1842, 0.2524, -0.4636]) * np.sign(obs[10])
    action_b_b = np.zeros(6) + np.array([-0.2702, -0.01829, 1.073, -0.04532, -0.08506, 1.979]) * obs[9] * obs[0]
    action_b_b = np.zeros(6)
    # coverage: conditional `obs[0] > -0.3801`: true 100% of 110,000 tests (always true)
    # coverage: conditional `obs[5] < -0.1688`: never reached
    return 0.5729 * (action - action * obs[9] + np.array([6.61, 0.02102, 0.08692, 0.8041, -(1.361 * np.abs(obs[8])), -0.4085]) * np.sign(obs[9])) + -0.138 * (action_b - action_b * (obs[9] + 0.9059 * obs[0]) + np.array([5.529, 0.1131, 0.2974, 0.4272, -0.1312, -1.096]) * np.sign(obs[9])) + np.array([0.1768, 0.1664, -0.9484, -0.03035, 0.01482, -0.06905]) * obs[3] + np.array([-0.2155, 0.2508, 0.01201, -0.5773, -0.9061, 0.05471]) * obs[7] if obs[0] > -0.3801 else 0.3162 * (action_b - action_b * obs[9] + np.array([2.561, -0.1676, 0.04934, 0.3572, -(0.9461 * np.abs(obs[8] - 0.167 * np.sign(obs[13]))), -0.3268]) * np.sign(obs[9])) + -0.129 * (action_b_b - action_b_b * obs[9] + np.array([2.407, 0.5143, 0.645, 0.4965, -0.3043, -2.866]) * np.sign(obs[9])) + np.array([0.02501, 0.5241, -0.5451, 0.04186, 0.1082, -0.02774]) * obs[3] if obs[5] < -0.1688 else 0.3835 * (action_b_b - action_b_b * obs[9] + np.array([7.144, -0.02744, 0.2076, 0.836, -(2.536 * np.abs(obs[8])), -0.6361]) * np.sign(obs[9])) + -0.1651 * (action_b_b - action_b_b * (obs[9] + 0.9572 * obs[0]) + np.array([0.4675, 0.3469, 0.1561, 0.2584, -0.1479, -2.018]) * np.sign(obs[9])) + np.array([0.2005, 0.3231, -1.105, -0.06185, 0.06304, -0.0824]) * obs[3]