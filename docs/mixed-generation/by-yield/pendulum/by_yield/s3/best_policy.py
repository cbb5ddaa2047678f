# colmo best policy for pendulum: training score 819.50, held-out 850.91 after 178 samples
import numpy as np

def policy(obs):
    action = 0.02439
    return 1.222 * obs[0] - np.sign(-1.249 * obs[1]) + 3.809 * np.sign((-2.389 * obs[1] + -4.228 * obs[2]) * obs[0] + 3.249 * obs[2])