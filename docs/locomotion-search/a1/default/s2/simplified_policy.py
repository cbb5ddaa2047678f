# colmo: the best policy of a1 simplified: training score 147.63, held-out 142.78
import numpy as np

def policy(obs):
    action = np.zeros(12)
    return action + 0.0279 * obs[22]
