# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/budget4/mutate/s1/input_policy.py:
# training score 251.14 -> 92.54, held-out 242.55 -> 92.85; 127 -> 28 AST nodes
import numpy as np

def policy(obs):
    return np.array([-0.05216, -0.1128, -0.8684, 0.05027, -0.9584, -0.9899]) * np.sign(obs[2]) + obs[7]
