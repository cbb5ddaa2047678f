# colmo: the best policy of cheetah simplified: training score 232.52, held-out 152.31
import numpy as np

def policy(obs):
    action = np.zeros(6) - 0.4631 * (obs[13] + 0.3283 * (2.291 - 0.05173 * (2.434 * obs[1] + 6.149 * obs[14]) * obs[5]) + (0.4758 * (np.clip((obs[3] + 0.09535 * obs[13] * obs[14]) ** 2, -0.023495674997057306, 1.485) + 1.252 * np.tanh(obs[2])) + 0.4176 * np.sin(obs[9]))) + 3.964 * obs[9]
    action_b = np.zeros(6) - 0.3344 * (obs[13] + 0.2129 * (5.849 - 0.1425 * obs[13] * obs[5]) + (0.6217 * np.clip((obs[3] + 0.06495 * obs[13] * obs[14]) ** 2, -0.2434, 0.8478) + 0.4773 * np.sin(0.2833 * obs[15] + (1.05 * obs[2] - 4.023 * np.cos(obs[7]))))) + 0.7006 * obs[9]
    return action - 0.1753 * obs[0] * obs[6] if obs[9] * obs[8] > 0.1394 else action_b - 0.1718 * obs[0] * obs[6]
