# colmo: the best policy of cheetah simplified: training score 235.79, held-out 225.28
import numpy as np

def policy(obs):
    action_b = -0.09473 * obs[11]
    return obs[7] + np.array([11.06, 1.962, 1.0, 0.1153, 4.246 * obs[11], -10.35]) * np.arctan2(np.sign(obs[14]), obs[2]) if obs[10] > -0.2134 else action_b + np.array([5.242, 1.687, -0.1445 - 2.056 * obs[4], 0.01183, 0.03968, -7.206]) * np.sign(obs[14])
