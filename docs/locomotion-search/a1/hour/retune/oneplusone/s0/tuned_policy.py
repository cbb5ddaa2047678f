# tuned by colmo-optimize (gfo=oneplusone): training score 152.62, held-out 138.39
import numpy as np

def policy(obs):
    action = -(-0.6921 * obs[1] * obs[26] + obs[26]) + np.array([-0.08145, -0.2331, 0.01063, -0.1091, 0.2385, 0.2197, -0.3311, 0.1761, -0.1519, -0.2361, -0.2833, -1.334]) * np.arctan2(obs[25], obs[20])
    return action
