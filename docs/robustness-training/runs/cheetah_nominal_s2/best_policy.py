# colmo best policy for cheetah: training score 78.95, held-out 63.72 after 25 samples
import numpy as np

def policy(obs):
    action = np.zeros(6)
    return action + 7.44 * obs[14]