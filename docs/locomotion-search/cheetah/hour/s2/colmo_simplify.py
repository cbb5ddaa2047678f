# simplified by colmo-simplify (tolerance 0.01, gfo=oneplusone) from /work/main/docs/locomotion-search/cheetah/hour/s2/best_policy.py:
# training score 282.70 -> 281.06, held-out 276.60 -> 275.40; 168 -> 44 AST nodes
import numpy as np

def policy(obs):
    return 0.3349 * (np.array([-0.2635, 3.418, -1.276, 0.04249, 0.5516, 0.08842]) * obs[12]) + np.array([-0.02676, 0.2746, -0.2541, -0.6242, 0.5045, -0.0456]) * np.arctan2(obs[2], obs[15])
