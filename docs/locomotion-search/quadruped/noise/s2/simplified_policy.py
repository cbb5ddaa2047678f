# colmo: the best policy of quadruped simplified: training score 126.94, held-out 121.58
import numpy as np

def policy(obs):
    action = -(np.array([7.408, -0.04159, -4.336, -5.69, -1.628, obs[47] + 0.1549 / obs[13], 7.033, -0.2139, 2.489, -8.059, 0.8961, 5.175]) * obs[77])
    return action
