# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/budget2/by_yield/s2/input_policy.py:
# training score 277.65 -> 84.41, held-out 273.61 -> 107.23; 245 -> 34 AST nodes
import numpy as np

def policy(obs):
    action = np.array([0.1899, -0.03925 * obs[11], 0.4975, -0.129, -25.56, -0.7963]) * np.arctan2(obs[5], obs[14])
    return action
