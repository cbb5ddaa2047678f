# colmo: the best policy of cheetah simplified: training score 207.45, held-out 194.36
import numpy as np

def policy(obs):
    action = 173.3 * obs[1] + obs[7] * np.sign(obs[6]) + np.array([0.6265, -3.089, 0.7777, 0.1445, -2.176, -0.2757]) * np.tanh(np.arctan2(obs[6], 0.0))
    return action
