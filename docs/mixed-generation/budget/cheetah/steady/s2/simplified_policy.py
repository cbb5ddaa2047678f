# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/budget2/steady/s2/input_policy.py:
# training score 235.80 -> 114.34, held-out 226.84 -> 121.78; 210 -> 36 AST nodes
import numpy as np

def policy(obs):
    return obs[7] + np.array([11.06, 1.962, 1.0, 0.1153, obs[11], -10.35]) * np.arctan2(np.sign(obs[14]), obs[2])
