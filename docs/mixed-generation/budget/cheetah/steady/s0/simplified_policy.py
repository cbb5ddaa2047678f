# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/budget2/steady/s0/input_policy.py:
# training score 273.64 -> 39.72, held-out 264.27 -> 38.07; 162 -> 33 AST nodes
import numpy as np

def policy(obs):
    action = 1.0
    return action + np.array([-123.7, -8.603, -5.287, 0.2034, 9.411, 6.68]) * np.tanh(obs[16]) ** 2 + action
