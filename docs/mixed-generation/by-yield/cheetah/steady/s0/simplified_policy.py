# colmo: the best policy of cheetah simplified: training score 271.30, held-out 264.88
import numpy as np

def policy(obs):
    if obs[8] > -0.1693:
        action = ([-43.47, 0.9837, 1.276, 3.046, 1.573, -25.05] - -7.659 * obs[0]) * obs[4] + 0.231 * obs[4]
    else:
        action = 0.7259 * obs[11] - obs[4]
    return action + np.array([-123.7, -8.603, -5.287, 0.2034, 9.411, 6.68]) * np.tanh(obs[16] - 0.06841 * obs[4] * obs[15]) ** 2 + np.array([0.0398, 3.39, -1.128, 1.634, 1.284, 0.7224]) * action
