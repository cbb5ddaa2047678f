# colmo: the best policy of pendulum simplified: training score 827.10, held-out 817.83
import numpy as np

def policy(obs):
    if np.sin(obs[0]) < 0.692:
        action = obs[2]
    else:
        action = -14.56 * obs[2] + -16.11 * obs[1]
    return action
