# colmo best policy for pendulum: training score 789.10, held-out 773.23 after 419 samples
import numpy as np

def policy(obs):
    action = 0.8054 * obs[1] - -6.116 * obs[1]
    if obs[1] ** 2 < 0.4272:
        return (0.5045 + -23.97 * obs[0]) * obs[2]
    elif obs[1] > -3.318:
        return (13.05 + -3.355 * obs[0]) * np.sign(obs[2]) - 0.0675 * np.tanh(obs[0])
    else:
        return (-12.17 + -14.58 * obs[0]) * np.sign(obs[2]) - -0.1792 * np.tanh(obs[0]) - -0.502 * action