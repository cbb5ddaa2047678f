# colmo: the best policy of pendulum simplified: training score 839.60, held-out 664.21
import numpy as np

def policy(obs):
    action = 0.1671
    if np.abs(obs[2]) + -4.507 * obs[0] < -0.5389:
        return action - 11.97 * (obs[1] - -2.005 * obs[2] * obs[0]) + 0.3294
    else:
        return 17.46 * np.arctan2(obs[2], obs[1])
