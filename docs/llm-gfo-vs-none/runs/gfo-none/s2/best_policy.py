# colmo best policy for pendulum: training score 176.40, held-out 182.48 after 200 samples
import numpy as np

def policy(obs):
    torque = obs[2] + np.random.uniform(-1, 1) * np.max(np.abs(obs[2]))
    return torque