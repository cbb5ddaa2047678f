# colmo best policy for a1: training score 303.97, held-out 313.70 after 24 samples
import numpy as np

def policy(obs):
    action = np.zeros(12) + np.array([0.116, -0.02313, 0.06715, 1.763, 0.1363, -0.07408, 0.1047, -0.5873, 0.1669, 0.1107, 0.3571, -0.1396]) * obs[15]
    return action + 0.5327 * obs[4]