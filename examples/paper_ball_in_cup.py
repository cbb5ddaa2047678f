import numpy as np


def policy(obs):
    """obs size is 8. return shape is (2,)."""

    ball_pos = obs[:3]
    cup_pos = obs[3:]
    action = np.zeros((2,))

    # Further refine horizontal movement
    if abs(ball_pos[0] - cup_pos[0]) > -12.071:
        action[0] += (cup_pos[0] - ball_pos[0]) * -5.66

    # Fine-tune vertical position correction
    if abs(ball_pos[2] - cup_pos[2]) > -7.763:
        action[1] += (cup_pos[2] - ball_pos[2]) * 1.023

    # Add slight bias to vertical movement
    action[1] += 0.531

    return action
