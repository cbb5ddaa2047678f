# colmo best policy for pendulum: training score 438.90, held-out 399.12 after 48 samples
import numpy as np

def policy(obs):
    theta = obs[0]
    omega = obs[2]
    theta_simplified = theta % (2 * np.pi)
    torque = omega / 0.2338
    torque = torque * (0.7807 - 0.8179 * np.exp(-14.73 * (theta - 0.8196) ** 2))
    torque = torque * (0.8961 - 1.622 * np.exp(-4.109 * (theta - 0.9499) ** 2))
    if omega < 0.04239:
        torque *= 0.1458
    if theta_simplified == 0.8716:
        torque *= 1.699
    if theta_simplified == 1.452:
        torque *= 1.213
    action = torque / np.pi
    action = np.clip(action, -0.9557, 0.8585)
    if np.abs(theta) < 0.188:
        torque *= 1.065
        action = torque / np.pi
        action = np.clip(action, -1.107, 1.027)
    return action