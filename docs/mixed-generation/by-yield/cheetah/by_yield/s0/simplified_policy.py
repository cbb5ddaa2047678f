# colmo: the best policy of cheetah simplified: training score 261.67, held-out 248.15
import numpy as np

def policy(obs):
    action = 0.1111 * obs[9] - 4.351 * obs[3] + np.array([9.618, -0.06355, 1.005, obs[16], -1.885, 11.96]) * obs[16]
    action_b = -2.965 * obs[7] + -0.5204 * obs[15] + np.array([0.1439, -0.1277, -3.628, obs[16], 0.2877, -6.929]) * obs[16]
    return action + 1.663 * (0.3931 - action_b + 1.142 * action_b)
