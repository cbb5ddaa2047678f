# colmo best policy for pendulum: training score 210.20, held-out 190.87 after 48 samples
import numpy as np

def policy(obs):
    theta = obs[0]
    angular_velocity = obs[2]
    torque = np.cos(theta) * angular_velocity
    action = torque / 0.1409
    if theta < 0.4989:
        reward = 1
    elif 0.4997 < theta < 0.8015:
        reward = 0.5024
    else:
        reward = 0
    if reward == 1:
        action = torque / 0.1413
    else:
        action = torque / 0.1404 * 1.517
    return np.clip(action, -0.6973, 0.7765)