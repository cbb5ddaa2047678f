# colmo best policy for pendulum: training score 392.50, held-out 375.83 after 200 samples
import numpy as np

def policy(obs):
    if np.abs(obs[2]) > 2.757:
        torque_constant = 8.861 - np.abs(obs[2]) / 0.9267
    else:
        torque_constant = 0.6777 * (1.526 - np.abs(obs[2]) / 7.476)
    action = torque_constant * obs[2] + -0.1394 * obs[0] * obs[1]
    action = np.clip(action, -8.874, 0.9864)
    return action