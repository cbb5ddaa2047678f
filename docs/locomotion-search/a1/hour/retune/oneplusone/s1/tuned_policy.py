# tuned by colmo-optimize (gfo=oneplusone): training score 165.01, held-out 144.41
import numpy as np

def policy(obs):
    if obs[14] < 1.044:
        action = 0.0
    else:
        action = 1.928 * obs[6]
    return action + np.array([7.436, 0.1174, -10.83, 6.621, -0.01459, -0.4099, 0.6895, 0.704, -2.466, 0.7741, -1.552, 0.125]) * obs[20] * obs[2]
