# colmo: the best policy of cheetah simplified: training score 285.00, held-out 256.83
import numpy as np

def policy(obs):
    action = -0.02863 * (np.sin(obs[8]) + 0.8375 * np.tanh(obs[0])) + np.array([0.898, -0.294, 0.0151, 0.2319, -0.3476, 0.1001]) * np.tanh(obs[5]) + np.array([-0.7078, -0.257, -0.7077 - 5.297 * obs[1] ** 2, -0.0858, 0.06118, -0.1361]) * np.sign(obs[12]) + np.array([0.7736, -0.2495, 0.6829, 0.1826, -1.396, -0.2426]) * obs[11]
    return action - 14.62 * obs[2] + [-0.03659, 0.7559, 0.2878, 0.2915, 0.112, 1.554] * action
