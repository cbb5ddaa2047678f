# colmo: the best policy of pendulum simplified: training score 752.40, held-out 778.63
import numpy as np

def policy(obs):
    action_b = 17.83 - 27.27 * obs[2] - 10.69 * np.sin(obs[2])
    if obs[2] < 0.4524:
        action_b_b = 4.65 - -13.41 * np.cos(obs[1])
    else:
        action_b_b = 7.429 - -19.4 * obs[1]
    return 0.258 * action_b + 0.258 * (-(2.036 + -11.74 * obs[0]) * (1.497 * action_b)) - 4.112 * action_b_b + 74.92 * obs[2]
