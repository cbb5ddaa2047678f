# colmo: the best policy of cheetah simplified: training score 206.85, held-out 155.28
import numpy as np

def policy(obs):
    action = -0.6885 * np.sign(obs[6])
    return action + np.array([-1.185, -0.07275, -2.475, 0.571, 0.1517, 0.08173 - 4.915 * obs[10]]) * np.arctan2(obs[3], obs[2])
