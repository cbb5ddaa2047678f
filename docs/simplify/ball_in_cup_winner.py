# colmo best policy for ball_in_cup: training score 855.10, held-out 542.01 after 300 samples
import numpy as np

def policy(obs):
    action = np.zeros(2)
    return action - 7.58 * obs[6] * obs[4]