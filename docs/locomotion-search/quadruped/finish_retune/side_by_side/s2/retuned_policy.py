# colmo: the simplified policy of quadruped re-tuned (gfo=oneplusone, 541 evaluations): training score 131.60, held-out 126.84
import numpy as np

def policy(obs):
    action = -(np.array([2.648, 0.1379, -4.353, -3.236, -2.682, -2.149, 7.009, -0.6135, 7.817, -3.408, 0.9335, 1.555]) * obs[77])
    return action
