# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/c10always/s2/input_policy.py:
# training score 285.00 -> 281.74, held-out 256.83 -> 262.34; 124 -> 70 AST nodes
import numpy as np

def policy(obs):
    action = -0.02863 * (np.sin(obs[8]) + 0.8375 * obs[0]) + 0.2319 * np.eye(6)[3] * np.tanh(obs[5]) + np.array([0.7736, -0.2495, 0.6829, 0.1826, -1.396, -0.2426]) * obs[11]
    return action - 14.62 * obs[2] + np.eye(6)[3] * action
