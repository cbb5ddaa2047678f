# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/budget4/steady/s2/input_policy.py:
# training score 235.80 -> 134.56, held-out 226.84 -> 137.10; 210 -> 74 AST nodes
import numpy as np

def policy(obs):
    action_b = -0.09473 * obs[11]
    return obs[7] + np.array([11.06, 1.962, 1.0, 0.1153, obs[11], -10.35]) * np.arctan2(np.sign(obs[14]), obs[2]) if obs[10] > -0.2134 else action_b - 2.056 * obs[4] * np.eye(6)[2] * np.arctan2(1.0, np.cos(obs[2]))
