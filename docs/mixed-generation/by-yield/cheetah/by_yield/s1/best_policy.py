# colmo best policy for cheetah: training score 284.31, held-out 278.11 after 124 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = -52.82
    # coverage: if `np.abs(obs[10]) > 0.4394`: true 71% of 110,000 tests
    if np.abs(obs[10]) > 0.4394:
        # coverage: `np.array([-91.8, -11.39, -(41.79 + 0.4972 * obs[10]), 0.2...`: divisor never 0 in 468,816 values
        action_b = np.zeros(6) + np.array([-91.8, -11.39, -(41.79 + 0.4972 * obs[10]), 0.2509, 76.37, -11.82]) / obs[3] - 0.1363 * obs[2] + np.array([3.373, -0.2439, -0.1376 - 0.1351 * obs[9], -0.01482, -0.1963, 1.593]) * np.sin(0.1269 * obs[12])
    else:
        action_b = np.zeros(6) + np.array([-38.09, -2.628, -26.93, 0.5532, -6.252, -27.09]) * obs[3] - 0.07183 * obs[2] + np.array([0.4425, -0.6972, -0.253 - 0.09928 * obs[9], 0.008192, -0.213, 1.098]) * np.sin(0.1518 * obs[12]) - 0.2408 * obs[10] * obs[1]
    action_b = np.zeros(6) + np.array([-72.44, -9.537, -91.9, 0.1793, 13.4 - 0.9167 * obs[9] * obs[5], np.abs(-14.72)]) * obs[3] + np.array([1.362, 2.315, -0.2434 - 2.611 * obs[9], 0.07586, -0.0102, 1.41]) * np.sin(0.3306 * obs[12])
    # coverage: conditional `obs[3] > 0.8253`: true 0% of 110,000 tests (never true)
    return (action + np.array([-1.652, -5.394, 8.361, 7.588, -2.501, -0.1246]) * obs[6] if obs[3] > 0.8253 else action_b + 0.5086 * (-(2.272 - 0.2966 * np.sign(obs[3])) * np.tanh(obs[9])) * obs[6]) + np.array([-0.2094, -0.3389, -0.1102, 0.01142, 0.2325, -1.775]) * np.arctan2(obs[4], obs[15])