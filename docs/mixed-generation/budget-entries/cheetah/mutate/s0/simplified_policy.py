# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/budget4/mutate/s0/input_policy.py:
# training score 229.37 -> 231.29, held-out 227.18 -> 228.03; 71 -> 49 AST nodes
import numpy as np

def policy(obs):
    return 0.6778 * np.abs(obs[5]) * obs[9] - 0.2655 * obs[1] + np.array([1.733, 0.1936, 2.857, 1.768, -0.08255, 1.0]) * np.sign(obs[9]) - 0.02019 * obs[15]
