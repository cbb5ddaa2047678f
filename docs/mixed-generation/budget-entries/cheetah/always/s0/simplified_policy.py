# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/c10always/s0/input_policy.py:
# training score 301.45 -> 301.45, held-out 310.61 -> 310.61; 67 -> 21 AST nodes
import numpy as np

def policy(obs):
    return np.array([-21.28, -1.558, -5.349, 0.4344, 13.56, 1.517]) * obs[3]
