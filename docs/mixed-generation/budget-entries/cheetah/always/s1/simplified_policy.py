# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/c10always/s1/input_policy.py:
# training score 249.18 -> 245.70, held-out 250.19 -> 245.67; 177 -> 58 AST nodes
import numpy as np

def policy(obs):
    action = -4.579 + np.sin(obs[6])
    return action + (18.32 - 21.22 * (obs[16] + obs[1])) * np.arctan2(obs[2], np.abs(obs[8])) + np.array([1.139, -1.349, 1.458, 0.1433, -0.555, 0.3723]) * obs[11]
