# colmo best policy for cheetah: training score 62.54, held-out 77.67 after 25 samples
import numpy as np

def policy(obs):
    action = np.zeros(6)
    return action + obs[12] + 2.13 * obs[6]