# colmo best policy for quadruped: training score 103.54, held-out 103.54 after 153 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: `-5.333e-05 / obs[68]`: divisor never 0 in 110,000 values
    action = -2.505 * obs[1] - -5.333e-05 / obs[68]
    return action + np.array([0.001882, 0.0491, 3.304, -0.5408, 0.8448, -0.494, 6.119, -3.341, -0.8927, -0.1455, -0.6955, -1.465]) * obs[33] + np.array([0.1764, -0.1346, -0.3487, 1.453, 0.5151, 0.44, -0.3092, -0.1301, 0.3625, -(0.176 - 0.149 * np.abs(obs[10])), -0.1125, 0.2917]) * obs[8]