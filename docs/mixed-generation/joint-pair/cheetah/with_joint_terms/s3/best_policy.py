# colmo best policy for cheetah: training score 217.50, held-out 179.68 after 219 samples
import numpy as np

def policy(obs):
    action = 0.4368 * obs[8] - -3.022 * obs[2]
    return action - np.array([31.07, 4.037, 31.17, -24.59, 13.84, -(0.2817 * np.sign(obs[16]) - 25.2 * obs[1])]) * obs[3]