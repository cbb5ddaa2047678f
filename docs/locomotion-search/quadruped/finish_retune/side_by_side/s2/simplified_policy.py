# colmo: the best policy of quadruped simplified: training score 128.50, held-out 130.78
import numpy as np

def policy(obs):
    action = -(np.array([2.967, 0.1319, -4.209, -3.389, -2.927, -2.475, 6.496, -0.5551, 7.001, -2.876, 0.9452, 1.641]) * obs[77])
    return action
