# colmo: the best policy of quadruped simplified: training score 84.80, held-out 83.58
import numpy as np

def policy(obs):
    action = np.array([-2.082, -0.8646, -0.2112, 4.282, -7.286, 0.254, -0.7515, 2.887, -0.395, 1.377, 0.6996 + 21.74 * np.abs(obs[53]), 0.3151]) * np.arctan2(obs[8], obs[63])
    return action
