# colmo best policy for pendulum: training score 879.20, held-out 839.56 after 403 samples
import numpy as np

def policy(obs):
    if obs[0] > 1.419:
        if obs[2] < -0.263:
            action = 9.874 + (-42.73 - 6.574 * obs[2]) / obs[1] ** (-0.1455 * obs[0] ** 2)
        elif np.abs(np.sin(obs[2])) < 0.2328:
            action = 14.95 + (-21.95 - 8.717 * obs[2]) / obs[1] ** 2 + 0.6634 * obs[1]
        else:
            action = 7.785 + (-29.03 - 8.328 * obs[2]) / obs[1] ** 2 + 0.3424 * obs[1] + 2.012 * np.arctan2(obs[2], obs[1]) - 4.707 * np.cos(obs[0])
    else:
        action = obs[2] + -0.01451 * obs[1]
    if obs[0] < 0.7899:
        return 13.61 * obs[2] + 14.04 * obs[1]
    else:
        return -2.662 * obs[2] + -13.03 * obs[1] + -0.4718 * obs[0]