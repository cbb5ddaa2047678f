# colmo best policy for quadruped: training score 14.63, held-out 11.61 after 300 samples
import numpy as np

def policy(obs):
    action = np.cos(np.zeros(12) - 1.83 * (np.sin(obs[53]) - np.cos((0.591 * np.cos(obs[35]) + (1.18 + 3.46 * obs[10] ** 2) * obs[35]) * obs[29]))) + 1.34 * (4.69 * obs[24])
    return action