# colmo best policy for cheetah: training score 105.88, held-out 76.84 after 300 samples
import numpy as np

def policy(obs):
    action = np.zeros(6)
    return action - 6.12 * action + (0.986 + (0.352 * np.tanh(np.abs(obs[9])) + 0.424 * action - 1.01 * obs[0])) * obs[11]