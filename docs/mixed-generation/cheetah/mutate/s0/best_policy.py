# colmo best policy for cheetah: training score 231.50, held-out 211.60 after 302 samples
import numpy as np

def policy(obs):
    action = np.zeros(6) - (np.sin(-0.3536) * obs[11] - 31.86 * obs[1] + 4.009 * obs[5]) + 4.653 * obs[6]
    return action