# colmo best policy for cheetah: training score 73.65, held-out 86.87 after 25 samples
import numpy as np

def policy(obs):
    action = np.zeros(6) + 0.74 * (obs[12] + 6.34 * obs[14])
    return action