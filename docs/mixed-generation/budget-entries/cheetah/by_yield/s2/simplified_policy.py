# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/budget4/by_yield/s2/input_policy.py:
# training score 277.65 -> 268.10, held-out 273.61 -> 273.54; 245 -> 43 AST nodes
import numpy as np

def policy(obs):
    action = np.array([0.1899, -0.0596, 0.4975, -0.129, -25.56, -0.7963]) * np.arctan2(obs[5], obs[14])
    return action + 11.47 * np.eye(6)[3] * obs[6]
