# simplified by colmo-simplify (tolerance 0.01, gfo=oneplusone) from /work/main/docs/locomotion-search/cheetah/hour/s1/best_policy.py:
# training score 327.01 -> 327.01, held-out 311.32 -> 311.32; 261 -> 110 AST nodes
import numpy as np

def policy(obs):
    action = -5.98 * np.tanh(obs[0])
    return 0.5759 * (action + np.array([0.08097, -0.1523 * obs[10], -1.984, 0.3227, -0.6301, -0.6567]) * np.sign(obs[2]) + np.array([0.6309, -0.1661, -0.5556, 0.6942, -0.104, -2.865]) * np.arctan2(obs[7], obs[11])) + 0.7043 * (np.array([-0.09175, -0.07468, -0.7754, 0.1011, -0.7262, -1.324]) * np.sign(obs[2]) + np.array([0.7123, -0.2407, -0.253, 0.6184, -0.2862 + 0.133 * obs[3], -1.08]) * np.arctan2(obs[7], obs[11]))
