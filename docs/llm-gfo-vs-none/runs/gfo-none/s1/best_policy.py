# colmo best policy for pendulum: training score 196.50, held-out 178.59 after 200 samples
import numpy as np

def policy(obs):
    m = 1.0
    l = 0.5
    g = 9.8
    kp = 3.5
    kd = 0.65
    theta = obs[0]
    omega = obs[2]
    omega_next = omega + kp * omega - kd * omega + g * np.sin(theta)
    torque = 0.6 * (l * m * omega_next) - g * l * np.sin(theta)
    torque = np.clip(torque, -1.0, 1.0)
    return torque