# colmo best policy for quadruped: training score 82.01, held-out 84.45 after 64 samples
import numpy as np

def policy(obs):
    action = np.zeros(12) + np.array([0.9247, 0.1891, 0.08064, 0.6421, -0.4598, 0.2602, -0.273, 0.2542, 0.1762, 0.2903, -0.2375 + 2.143 * np.abs(obs[53]), -0.1548]) * np.arctan2(obs[8], obs[63]) + np.array([-1.221, -0.2931, -0.4744, 0.9158, -0.4515, 0.9363, -0.6589, 3.44 * np.abs(obs[75]), -0.1134, -0.1903, 0.2338, 0.1419]) * obs[15] * obs[1]
    return action