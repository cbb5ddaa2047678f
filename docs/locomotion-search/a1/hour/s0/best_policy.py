# colmo best policy for a1: training score 151.52, held-out 138.13 after 137 samples
import numpy as np

def policy(obs):
    action = np.zeros(12) - (-0.6928 * obs[1] * obs[26] + obs[26]) + np.array([-0.08083, -0.2332, 0.01044, -0.1091, 0.2387, 0.2202, -0.3299, 0.176, -0.1517, -0.2364, -0.2845, -1.336]) * np.arctan2(obs[25], obs[20])
    return action