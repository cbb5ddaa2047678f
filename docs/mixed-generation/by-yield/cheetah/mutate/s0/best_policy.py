# colmo best policy for cheetah: training score 229.37, held-out 227.18 after 177 samples
import numpy as np

def policy(obs):
    action = np.zeros(6)
    return action - -0.6778 * np.abs(obs[5]) * obs[9] + -0.2655 * np.sin(obs[1]) + np.array([1.733, 0.1936, 2.857, 1.768, -0.08255, -(0.07587 + 8.308 * obs[2])]) * np.sign(obs[9]) + 0.0106 * (action + -1.905 * obs[15])