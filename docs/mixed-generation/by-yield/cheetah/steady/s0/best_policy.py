# colmo best policy for cheetah: training score 273.64, held-out 264.27 after 243 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `obs[8] > -0.1693`: true 98% of 110,000 tests
    if obs[8] > -0.1693:
        # coverage: `np.clip(np.sin(np.zeros(6)), -5.932, 2.758)`: changed 0% of 646,500 values (0% raised, 0% lowered)
        action = np.clip(np.sin(np.zeros(6)), -5.932, 2.758) + ((np.array([-43.47, 0.9837, 1.276, 3.046, 1.573, -25.05]) - -7.659 * obs[0]) * obs[4] + 0.231 * obs[4])
    else:
        action = 0.7259 * obs[11] - 3.477 * obs[4]
    # coverage: if `obs[4] < 7.179`: true 100% of 110,000 tests (always true)
    if obs[4] < 7.179:
        return action + np.array([-123.7, -8.603, -5.287, --0.2034, 9.411, 6.68]) * np.tanh(obs[16] - 0.06841 * obs[4] * obs[15]) ** 2 + np.array([0.0398, 3.39, -1.128, 1.634, 1.284, 0.7224]) * action
    else:
        return action + (0.1163 * obs[15] - 0.2092 * obs[2]) * obs[7] + -0.7788 * np.abs(obs[7]) + np.array([0.7453, -0.9472, -0.1235, -0.1404, 0.2183, -0.08414]) * obs[7] ** 2