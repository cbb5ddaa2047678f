# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/c10simp/s2/input_policy.py:
# training score 251.74 -> 251.74, held-out 244.23 -> 244.23; 45 -> 33 AST nodes
import numpy as np

def policy(obs):
    action = 1.09 * obs[9]
    return np.sin(action) + np.array([37.48, 1.642, 8.868, 7.033, 62.84, 341.6]) * obs[1]
