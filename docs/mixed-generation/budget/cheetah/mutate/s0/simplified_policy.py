# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/budget2/mutate/s0/input_policy.py:
# training score 229.37 -> 231.33, held-out 227.18 -> 229.63; 71 -> 50 AST nodes
import numpy as np

def policy(obs):
    return -(-0.6565 * np.abs(obs[5]) * obs[9]) - 0.2726 * obs[1] + np.array([1.715, 0.1971, 2.719, 1.654, -0.08051, 1.006]) * np.sign(obs[9]) - 0.02265 * obs[15]
