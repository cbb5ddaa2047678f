# simplified by colmo-simplify (tolerance 0.01, gfo=oneplusone) from /work/main/docs/locomotion-search/cheetah/hour/s0/best_policy.py:
# training score 325.75 -> 325.75, held-out 309.65 -> 309.65; 554 -> 164 AST nodes
import numpy as np

def policy(obs):
    action = np.array([-0.1736, -0.1821, 1.308, -0.1484, -0.1357, 1.116]) * obs[9] * obs[0]
    action_b = np.array([-2.081, 0.1253, 1.142, 0.3205, -0.2179, 0.2435]) * obs[9] * obs[0] + np.array([0.09256, 0.2548, 0.1289, 0.114, 0.172, -0.323]) * np.sign(obs[10])
    return 0.5729 * (action - action * obs[9] + np.array([6.61, 0.02102, 0.08692, 0.8041, -(1.361 * np.abs(obs[8])), -0.4085]) * np.sign(obs[9])) + -0.138 * (action_b - action_b * (obs[9] + 0.9059 * obs[0]) + np.array([5.529, 0.1131, 0.2974, 0.4272, -0.1312, -1.096]) * np.sign(obs[9])) + np.array([0.1768, 0.1664, -0.9484, -0.03035, 0.01482, -0.06905]) * obs[3] + np.array([-0.2155, 0.2508, 0.01201, -0.5773, -0.9061, 0.05471]) * obs[7]
