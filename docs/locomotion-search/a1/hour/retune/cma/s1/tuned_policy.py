# tuned by colmo-optimize (gfo=cma): training score 176.02, held-out 152.41
import numpy as np

def policy(obs):
    if obs[14] < 0.1423:
        action = 0.0208
    else:
        action = 1.627 * obs[6]
    return action + np.array([8.745, 0.1014, -13.16, 4.911, -0.001623, -0.3875, 0.5859, 0.6687, -2.668, 0.5445, -1.62, 0.111]) * obs[20] * obs[2]
