# colmo: the best policy of quadruped simplified: training score 99.57, held-out 88.17
import numpy as np

def policy(obs):
    action = np.array([-2.043, -0.8559, -0.2003, 4.291, -7.255, 0.2454, -0.7506, 2.893, -0.3977, 1.376, 0.703 + 21.73 * np.abs(obs[53]), 0.3097]) * np.arctan2(obs[8], obs[63])
    return action
