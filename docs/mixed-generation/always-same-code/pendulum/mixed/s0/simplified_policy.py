# colmo: the best policy of pendulum simplified: training score 576.70, held-out 505.62
import numpy as np

def policy(obs):
    if obs[2] < -0.3606:
        action = -0.6589
    else:
        action = 1.387 + -2.62 * obs[0]
    if np.abs(np.arctan2(obs[1], obs[0])) > 0.106:
        return action
    else:
        return 1.865 * obs[1]
