# colmo: the best policy of a1 simplified: training score 146.50, held-out 140.16
import numpy as np

def policy(obs):
    action = np.zeros(12)
    return action - -0.04465 * (obs[22] - 0.3792 * np.arctan2(-0.4057 * np.abs(obs[13]), obs[16]))
