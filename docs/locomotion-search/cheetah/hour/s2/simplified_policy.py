# colmo: the best policy of cheetah simplified: training score 281.06, held-out 275.40
import numpy as np

def policy(obs):
    return 0.3349 * (np.array([-0.2635, 3.418, -1.276, 0.04249, 0.5516, 0.08842]) * obs[12]) + np.array([-0.02676, 0.2746, -0.2541, -0.6242, 0.5045, -0.0456]) * np.arctan2(obs[2], obs[15])
