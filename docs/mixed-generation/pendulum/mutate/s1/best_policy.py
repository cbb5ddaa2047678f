# colmo best policy for pendulum: training score 877.20, held-out 848.87 after 517 samples
import numpy as np

def policy(obs):
    if obs[0] > 0.7258:
        action = -0.02951 * obs[2]
    else:
        if obs[0] > 0.2994:
            action = -0.2915 * obs[2]
        elif obs[0] > -12.21 * obs[2] - -0.2884 * obs[1]:
            action = 2.776
        else:
            action = 7.121 * obs[2]
        action = 1.424 * obs[2] - 27.18 * -0.03467 * obs[1]
    if np.abs(action) > 0.215:
        return action
    else:
        return -4.179 * obs[2] - 0.9266 * action - 26.37 * obs[1]