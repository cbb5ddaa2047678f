# colmo: the simplified policy of quadruped re-tuned (gfo=oneplusone, 327 evaluations): training score 93.51, held-out 92.02
import numpy as np

def policy(obs):
    action = np.array([0.0963, -1.11, -0.05272, 6.756, -6.184, 0.4749, -0.08976, 0.6855, -0.5892, 3.276, 0.3323 + 5.51 * np.abs(obs[53]), 0.5529]) * np.arctan2(obs[8], obs[63])
    return action
