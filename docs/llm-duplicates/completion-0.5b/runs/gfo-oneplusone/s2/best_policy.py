# colmo best policy for pendulum: training score 182.90, held-out 186.60 after 48 samples
import numpy as np

def policy(obs):
    action = np.sign(obs[2]) * 0.9286
    return action