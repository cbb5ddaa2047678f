# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/c10simp/s0/input_policy.py:
# training score 206.48 -> 207.45, held-out 176.26 -> 194.36; 77 -> 48 AST nodes
import numpy as np

def policy(obs):
    action = 173.3 * obs[1] + obs[7] * np.sign(obs[6]) + np.array([0.6265, -3.089, 0.7777, 0.1445, -2.176, -0.2757]) * np.tanh(np.arctan2(obs[6], 0.0))
    return action
