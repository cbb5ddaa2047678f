# simplified by colmo-simplify (tolerance 0.01, at most 10 constants, gfo=oneplusone) from /work/runs/budget4/by_yield/s1/input_policy.py:
# training score 279.51 -> 273.96, held-out 279.16 -> 282.01; 271 -> 61 AST nodes
import numpy as np

def policy(obs):
    action_b = np.array([-72.44, -9.537, -91.9, 0.1793, 13.4, 14.72]) * obs[3] + 2.315 * np.eye(6)[1] * np.sin(0.3306 * obs[12])
    return action_b - 0.3389 * np.eye(6)[1] * np.arctan2(obs[4], obs[15])
