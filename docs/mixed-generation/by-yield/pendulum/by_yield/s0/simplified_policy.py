# colmo: the best policy of pendulum simplified: training score 858.60, held-out 845.27
import numpy as np

def policy(obs):
    action = np.sign(-3.789 * obs[1] - obs[2])
    if obs[0] > 0.7659:
        return action
    else:
        return obs[2]
