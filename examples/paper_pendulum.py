import numpy as np


def policy(obs):
    """obs size is 3. return shape is ()"""
    x1 = np.arctan2(-obs[1], obs[0])
    # Adjust action
    if np.abs(x1) > np.pi / 6.512:
        action = np.sign(obs[2])
    else:
        action = 9.437 * np.sin(x1) - 2.746 * obs[2]

    return action
