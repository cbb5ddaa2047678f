# colmo best policy for quadruped: training score 41.15, held-out 41.40 after 16 samples
import numpy as np

def policy(obs):
    action = np.zeros(12) + np.array([0.5686, 0.7268, -1.885, 4.872, -2.341, -2.813, -1.846, -2.997, -1.226, -1.598, 5.985, 3.119]) * obs[51]
    return action + np.array([0.03904, -3.192, 0.5288, 1.774, -0.06358, -0.4238, 6.136, -1.015, -1.611, -0.8795, 0.7322, 1.657]) * obs[52] ** 2