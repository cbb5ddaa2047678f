# colmo: the best policy of pendulum simplified: training score 878.20, held-out 849.15
import numpy as np

def policy(obs):
    if obs[0] > 0.7258:
        action = -0.02951
    else:
        action = obs[2] - -0.9423306 * obs[1]
    if np.abs(action) > 0.215:
        return action
    else:
        return -4.179 * obs[2] - 26.37 * obs[1]
