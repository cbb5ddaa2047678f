import numpy as np


def policy(obs):
    """obs size is 17: position (8), velocity (9).
    return shape is (6,)."""

    pos = obs[:3]
    vel = obs[3:6]
    ang_vel = obs[6:9]

    # Adjust forward control gain
    action = np.zeros(6)
    action[0] = -12.241 * vel[0]

    action[1] = -0.603 * ang_vel[0]  # Hip angle
    action[2] = 11.351 * ang_vel[1]  # Knee angle
    action[3] = -8.106 * ang_vel[2]  # Ankle angle

    # Introduce a new control term for balance
    action[4] = -12.268 * ang_vel[1]

    return action
