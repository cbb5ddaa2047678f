# colmo best policy for pendulum: training score 122.30, held-out 41.46 after 48 samples
import numpy as np

def policy(obs):
    theta, sin_theta, angular_velocity = obs
    action = np.sign(sin_theta) * np.sqrt(1.954) * angular_velocity + 10.89
    return action