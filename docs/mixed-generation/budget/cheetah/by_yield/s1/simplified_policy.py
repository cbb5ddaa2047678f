# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/budget2/by_yield/s1/input_policy.py:
# training score 279.51 -> 227.45, held-out 279.16 -> 224.06; 271 -> 31 AST nodes
import numpy as np

def policy(obs):
    action_b = np.array([-75.8, -6.145, -81.75, 0.1008, 10.29, 19.12]) * obs[3] + np.sin(obs[12])
    return action_b
