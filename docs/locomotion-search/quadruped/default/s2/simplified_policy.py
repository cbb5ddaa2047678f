# colmo: the best policy of quadruped simplified: training score 106.27, held-out 106.27
import numpy as np

def policy(obs):
    action = -2.505 * obs[1]
    return action + np.array([0.001882, 0.0491, 3.304, -0.5408, 0.8448, -0.494, 6.119, -3.341, -0.8927, -0.1455, -0.6955, -1.465]) * obs[33] + np.array([0.1764, -0.1346, -0.3487, 1.453, 0.5151, 0.44, -0.3092, -0.1301, 0.3625, -1.0, -0.1125, 0.2917]) * obs[8]
