# colmo best policy for cheetah: training score 86.10, held-out 76.08 after 25 samples
import numpy as np

def policy(obs):
    action = np.zeros(6)
    return action + 7.44 * obs[14]