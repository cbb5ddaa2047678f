# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/c10simp/s1/input_policy.py:
# training score 289.60 -> 288.62, held-out 257.98 -> 263.50; 76 -> 55 AST nodes
import numpy as np

def policy(obs):
    if obs[10] > -3.246 - 10.19 * obs[7] ** 2:
        action = np.zeros(6)
    else:
        action = 4.278
    return np.tanh(action + -0.02755 * obs[3]) + np.array([10.41, 0.0, 2.992, -0.1103, -14.28, -1.107]) * obs[7]
