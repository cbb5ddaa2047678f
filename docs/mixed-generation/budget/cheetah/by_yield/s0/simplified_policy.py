# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/budget2/by_yield/s0/input_policy.py:
# training score 260.94 -> 253.74, held-out 234.90 -> 236.99; 168 -> 52 AST nodes
import numpy as np

def policy(obs):
    action_b = -2.965 * obs[7] + -0.5204 * obs[15]
    return 0.1111 * obs[9] - 4.351 * obs[3] + np.array([9.618, -0.06355, 1.005, obs[16], -1.885, 11.96]) * obs[16] + 0.2361 * action_b
