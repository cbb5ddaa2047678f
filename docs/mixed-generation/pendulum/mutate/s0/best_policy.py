# colmo best policy for pendulum: training score 859.40, held-out 848.44 after 451 samples
import numpy as np

def policy(obs):
    if obs[0] > 0.4985:
        action = -(11.08 * obs[1] + 29.19 * obs[2])
    else:
        if obs[0] > 1.442:
            action_b = -(11.93 * obs[1] + 100.9 * obs[2])
        else:
            action_b = -(1.842 * obs[1] + -4.879 * obs[2]) + 13.99 * np.sign(0.46 * obs[1])
        action = -(-12.3 * np.sin(obs[0]) + -0.2781 * (obs[2] - 0.5004 * action_b)) + 13.35 * np.sign(0.854 * obs[1])
    if obs[0] > 0.7204:
        action_b = -(19.17 * obs[1] + 3.402 * obs[2])
    else:
        if obs[0] > 2.16:
            action_b_b = -(-5.933 * obs[1] + 59.36 * obs[2])
        else:
            action_b_b = -(0.3291 * obs[1] + -16.3 * obs[2]) + 8.399 * np.sign(0.01488 * obs[1])
        if obs[0] > 0.4562:
            action = -(3.778 * obs[1] + 35.11 * obs[2])
        else:
            if obs[0] > 1.202:
                action_b = -(13.47 * obs[1] + 42.07 * obs[2])
            else:
                action_b = -(0.6076 * obs[1] + -5.477 * obs[2]) + 6.481 * np.sign(0.7691 * obs[1])
            action = -(12.24 * np.sin(obs[0]) + -1.02 * obs[2]) + 4.893 * np.sign(0.9349 * obs[1])
        if np.abs(obs[0] * obs[1]) > -0.05927:
            action_b = -(obs[1] + -4.626 * obs[2]) + 2.352 * np.sign(0.1277 * obs[1])
        else:
            action_b = 1.749 * obs[0]
    return action_b