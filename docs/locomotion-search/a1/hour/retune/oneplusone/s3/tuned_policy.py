# tuned by colmo-optimize (gfo=oneplusone): training score 160.82, held-out 134.03
import numpy as np

def policy(obs):
    action = 0.09362 * obs[24] ** 2 + np.array([0.07755, 1.187, -(16.0 * obs[16] ** 2), -3.69, -0.5508, 0.3772, 5.029, -0.2426, 0.5331, 2.579, 0.218, -0.4387]) * obs[12] * obs[1]
    return action
