# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/budget2/mutate/s2/input_policy.py:
# training score 233.99 -> 147.42, held-out 217.52 -> 154.66; 251 -> 47 AST nodes
import numpy as np

def policy(obs):
    action_b = np.array([2.516, -0.04826, 0.2206, 0.8294, 0.1262, -0.07135]) * obs[11]
    return (1.0 if obs[4] < 0.1394 else action_b + action_b + obs[10] - obs[5] ** 2) + 0.08314 * action_b
