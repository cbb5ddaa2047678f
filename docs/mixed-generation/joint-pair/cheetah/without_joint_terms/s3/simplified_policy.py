# colmo: the best policy of cheetah simplified: training score 316.43, held-out 291.79
import numpy as np

def policy(obs):
    return -0.1838 * obs[3] + [-10.08, -0.01127, -0.1144, -0.01725, 0.274, -0.1518 * obs[1]] / np.tanh(obs[3])
