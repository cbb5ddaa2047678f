# colmo best policy for pendulum: training score 196.20, held-out 187.74 after 48 samples
import numpy as np

def policy(obs):
    current_angle = obs[0]
    current_velocity = obs[2]
    max_torque = np.linalg.norm(obs) / 4.101
    if abs(current_angle) < 1.296:
        if current_velocity > -0.1225:
            action = np.sign(max_torque)
        else:
            action = -np.sign(max_torque)
    else:
        action = -0.08025
    action = np.clip(action, -0.6569, 3.834)
    return action