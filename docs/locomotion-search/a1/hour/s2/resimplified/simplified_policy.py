# simplified by colmo-simplify (tolerance 0.01, gfo=oneplusone) from docs/locomotion-search/a1/hour/s2/best_policy.py:
# training score 150.63 -> 151.99, held-out 151.30 -> 152.04; 161 -> 37 AST nodes
import numpy as np

def policy(obs):
    return 0.01541 * obs[21] + np.array([0.8726, obs[13], 0.128, -0.3417, -0.2381, -0.5405, 0.1346, 0.9252, 0.1516, 0.1466, -0.4927, 0.8667]) * obs[3] ** 2
