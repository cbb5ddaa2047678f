# colmo: the best policy of pendulum simplified: training score 649.00, held-out 671.17
import numpy as np

def policy(obs):
    if obs[2] > -0.9067:
        action = -4.767 * obs[0]
    else:
        action = 0.2438 * obs[2] + 0.5462 * obs[0]
    if np.abs(obs[1]) - 4.204 > -4.138:
        if obs[0] < 0.1647:
            return action - -1.741 * obs[2]
        else:
            return action + 1.557 * (4.435 * np.sign(obs[1])) * action
    elif obs[0] > 0.8426:
        return -4.391 * obs[2] - -2.298
    else:
        return 7.314 * obs[1] - np.sign(19.55 * (-2.431 * obs[2])) - -0.4384 * obs[0] - 0.6439
