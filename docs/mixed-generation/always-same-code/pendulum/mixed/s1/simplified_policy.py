# colmo: the best policy of pendulum simplified: training score 724.80, held-out 669.96
import numpy as np

def policy(obs):
    action = 0.1803 * obs[2] - 0.4166 * obs[1]
    if np.abs(obs[2]) < 0.3671:
        return action + 0.3336 - 6.187 * (obs[1] - -1.367 * obs[2])
    else:
        return action - (2.255 - 0.0476 * (0.4369 + 0.1798 * (obs[0] - 3.246 * action))) * (obs[1] - -2.516 * obs[2] * obs[0]) + 5.005 * np.arctan2(obs[2], obs[1])
