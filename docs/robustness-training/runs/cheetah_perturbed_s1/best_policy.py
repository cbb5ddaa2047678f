# colmo best policy for cheetah: training score 80.58, held-out 69.23 after 25 samples
import numpy as np

def policy(obs):
    action = np.zeros(6)
    return (action - 6.89 * (-0.773 * obs[11] + 0.554 * obs[15])) * (5.66 * obs[10])