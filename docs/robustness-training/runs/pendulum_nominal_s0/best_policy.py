# colmo best policy for pendulum: training score 212.50, held-out 249.10 after 25 samples
import numpy as np

def policy(obs):
    if np.sin(obs[1]) > -0.15:
        return -4.42 * (obs[1] - (5.32 + 0.464 / obs[1] * obs[2]) * obs[2])
    else:
        return -4.42 * (obs[1] - (5.32 + 0.464 * obs[1] * obs[2]) * obs[2]) + 7.33 * np.abs(obs[2])