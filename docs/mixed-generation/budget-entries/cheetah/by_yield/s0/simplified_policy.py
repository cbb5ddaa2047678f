# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/budget4/by_yield/s0/input_policy.py:
# training score 260.94 -> 258.75, held-out 234.90 -> 237.76; 168 -> 63 AST nodes
import numpy as np

def policy(obs):
    action_b = -2.965 * obs[7] - obs[15] - 0.1277 * np.eye(6)[1] * obs[16]
    return obs[9] - 4.351 * obs[3] + np.array([9.618, -0.06355, 1.005, obs[16], -1.885, 11.96]) * obs[16] + 0.3931 + 0.142 * action_b
