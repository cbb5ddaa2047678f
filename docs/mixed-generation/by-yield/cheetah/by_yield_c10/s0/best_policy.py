# colmo best policy for cheetah: training score 206.48, held-out 176.26 after 335 samples
import numpy as np

def policy(obs):
    action = np.zeros(6) - -51.18 * obs[1] ** 2
    action = np.zeros(6) - -173.3 * obs[1] - 0.6266 * action * obs[6] + obs[7] * np.sign(obs[6]) + np.array([0.6265, -3.089, 0.7777, 0.1445, -2.176, -0.2757]) * np.tanh(np.arctan2(obs[6], obs[9]))
    return action