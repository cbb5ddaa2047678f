# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/budget4/mutate/s2/input_policy.py:
# training score 233.99 -> 154.53, held-out 217.52 -> 146.26; 251 -> 51 AST nodes
import numpy as np

def policy(obs):
    action = np.array([1.209, 0.0646, 0.2563, -0.05617, -0.1442, -0.04438]) * obs[11]
    action_b = -0.04826 * np.eye(6)[1] * obs[11]
    return action - obs[6] if obs[4] < 0.1394 else action_b + action_b
