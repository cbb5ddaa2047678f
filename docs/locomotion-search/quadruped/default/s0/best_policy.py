# colmo best policy for quadruped: training score 93.47, held-out 93.47 after 145 samples
import numpy as np

def policy(obs):
    action = np.zeros(12)
    return action + np.array([-67.72, -17.63, 111.9, -np.arctan2(obs[76], obs[66]), 8.29, 1.018, 29.12, -59.57, 0.5345, -8.718, -53.55, -6.888]) * obs[15] * obs[14]