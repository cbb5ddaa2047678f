# colmo: the best policy of cheetah simplified: training score 282.70, held-out 280.12
import numpy as np

def policy(obs):
    action = np.array([0.1899, -0.03925 * obs[11], 0.4975, -0.129, -25.56, -0.7963]) * np.arctan2(obs[5], obs[14])
    return action + np.array([-0.068, 0.2022, 0.1174, 7.422, 0.2798, -0.09979]) * obs[6]
