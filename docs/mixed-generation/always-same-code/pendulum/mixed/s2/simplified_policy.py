# colmo: the best policy of pendulum simplified: training score 734.50, held-out 766.60
import numpy as np

def policy(obs):
    action = 2.471
    return 1.457 - -3.949 * np.arctan2(-(1.033 + 1.865 * action) / obs[0] - 4.319 * np.arctan2(obs[2], obs[1]) + obs[0], obs[2]) * np.arctan2(obs[0], obs[2])
