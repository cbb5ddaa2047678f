# colmo best policy for cheetah: training score 70.13, held-out 72.68 after 25 samples
import numpy as np

def policy(obs):
    action = np.zeros(6) - 0.229 * (obs[6] - 0.874 * obs[16])
    return action