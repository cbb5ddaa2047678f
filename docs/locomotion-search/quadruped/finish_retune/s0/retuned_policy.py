# colmo: the simplified policy of quadruped re-tuned (gfo=oneplusone, 131 evaluations): training score 62.61, held-out 62.27
import numpy as np

def policy(obs):
    action = np.zeros(12) + np.array([0.4241, 0.5266, -1.997, 7.272, -2.517, -3.951, -2.072, -1.19, -1.382, -2.574, 5.673, 2.195]) * obs[51]
    return action + np.array([0.0511, -4.327, 0.5051, 3.171, -0.05216, -0.8267, 5.215, -1.381, -3.285, -0.8717, 0.1914, 1.476])
