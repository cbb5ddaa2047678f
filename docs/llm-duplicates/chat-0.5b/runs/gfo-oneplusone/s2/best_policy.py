# colmo best policy for pendulum: training score 30.60, held-out 36.35 after 48 samples
import numpy as np

def policy(obs):
    action = np.sign(-0.4511) - -0.1974
    return action