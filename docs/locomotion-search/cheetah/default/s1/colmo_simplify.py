# simplified by colmo-simplify (tolerance 0.01, gfo=oneplusone) from /work/main/docs/locomotion-search/cheetah/default/s1/best_policy.py:
# training score 319.19 -> 318.51, held-out 312.57 -> 308.73; 187 -> 107 AST nodes
import numpy as np

def policy(obs):
    action = -5.95 * obs[0]
    return 0.5848 * (action + np.array([0.07469, -0.1688 * obs[10], -1.879, 0.3291, -0.5926, -0.6891]) * np.sign(obs[2]) + np.array([0.645, -0.1756, -0.5727, 0.6883, -0.1122, -2.792]) * np.arctan2(obs[7], obs[11])) + 0.735 * (np.array([-0.09111, -0.08037, -0.7992, 0.09102, -0.6979, -1.285]) * np.sign(obs[2]) + np.array([0.7037, -0.2417, -0.2493, 0.6553, -0.2807 + 0.1319 * obs[3], -1.136]) * np.arctan2(obs[7], obs[11]))
