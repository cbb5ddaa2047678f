# colmo best policy for pendulum: training score 291.50, held-out 110.38 after 48 samples
import numpy as np

def policy(obs):
    action = np.tan(0.7494 * np.dot(obs, [2.135, 0.421, 0.9587]))
    return action