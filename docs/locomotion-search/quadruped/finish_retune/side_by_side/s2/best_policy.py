# colmo best policy for quadruped: training score 83.15, held-out 81.56 after 8 samples
import numpy as np

def policy(obs):
    action = np.zeros(12) - np.array([2.052, 0.7264, -3.146, -2.004, -2.032, -1.672, 4.495, -1.938, 3.185, -2.072, 1.657, 3.056]) * obs[77]
    return action