# colmo: the best policy of pendulum simplified: training score 791.60, held-out 523.87
import numpy as np

def policy(obs):
    return 0.6124 * (-0.3833 / (obs[1] + (-1.349 + 3.69 * obs[0]) * obs[0] * (-0.1064 * obs[2] + 1.831 * obs[1])) + 0.591 * obs[0] + obs[2] + 3.021 * (np.arctan2(obs[1], obs[2]) - -0.226 * obs[1])) + 2.21 * (-0.1995 / (obs[1] + 0.238 * obs[0] * obs[2]) + obs[2])
