# colmo best policy for pendulum: training score 790.20, held-out 818.69 after 540 samples
import numpy as np

def policy(obs):
    action = np.sin(-0.9214) / (obs[0] - 27.58 * obs[2]) + np.tanh(8.844 * obs[2])
    if 5.12 * obs[0] < 3.926:
        return action
    elif np.abs(np.arctan2(obs[2], np.tanh(obs[1]))) < 0.4194:
        if np.abs(action) > 1.131:
            if np.abs(obs[1]) < 0.1058:
                return action
            elif np.arctan2(obs[0], obs[2]) > -0.2336:
                return action + -0.3499 * np.arctan2(obs[2], obs[1]) * action
            else:
                return action + -1.011 * np.arctan2(obs[2], obs[1]) * action + 3.925 * np.sin(obs[1])
            return 5.64 * obs[2] - 0.01221 * obs[0]
        else:
            return -0.6524 * obs[0] - 0.1935 * obs[1]
    else:
        return -1.982 * obs[2] - 10.52 * obs[1]