# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/budget4/steady/s0/input_policy.py:
# training score 273.64 -> 116.88, held-out 264.27 -> 111.19; 162 -> 22 AST nodes
import numpy as np

def policy(obs):
    action = -36.64 * np.eye(6)[0] * obs[4]
    return action
