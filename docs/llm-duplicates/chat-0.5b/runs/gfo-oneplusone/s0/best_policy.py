# colmo best policy for pendulum: training score 71.90, held-out 41.75 after 48 samples
import numpy as np

def policy(obs):
    action = np.clip(np.random.normal(0, 1), -4.827, -0.9141)
    return action