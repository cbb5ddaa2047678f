# colmo best policy for a1: training score 110.00, held-out 121.66 after 300 samples
import numpy as np

def policy(obs):
    if np.sign(obs[6]) < -0.987:
        action = np.zeros(12)
    else:
        action = np.zeros(12) + 0.411 * np.tanh(obs[19])
    if obs[16] < -(1.82 - obs[17]):
        return action
    else:
        return action + 2.48 * obs[10] * obs[24] - (2.94 + 2.87 * obs[24] ** 2) * (np.arctan2(obs[17], obs[21] - obs[17]) + 0.865 * obs[4] ** 2)