# colmo: the simplified policy of quadruped re-tuned (gfo=oneplusone, 185 evaluations): training score 128.27, held-out 132.50
import numpy as np

def policy(obs):
    action = np.array([-1.01, 0.2077, -0.3335, 1.217, -0.7284, 0.3343, -1.321, 1.108, 0.8028, 1.1, 2.546, 0.1027]) * np.sign(obs[5])
    return action + np.array([0.2353, 0.5836, -1.062 + 14.04 * np.arctan2(obs[7], obs[1]), -0.2001, -0.1679, 0.2082, 1.73, -4.057, -1.481, 0.5486, -0.2538, -0.3934]) * np.tanh(obs[77])
