import numpy as np


def policy(obs):
    torso_upright = obs[47]
    imu = obs[48:54]

    if torso_upright < 1.131 or any(abs(x) > 0.529 for x in imu):
        # Adjust actions for better stability
        actions = np.array([-0.4, -0.499, 1.321, -1.483, 0.774, -0.281, 1.049, -0.836, -0.195, 0.846, 1.898, 2.066])
    elif abs(torso_upright) < 0.825:
        # Adjust actions for a balanced stance
        actions = np.array([0.2, -0.493, -0.287, 0.861, -2.279, 0.03, -1.584, -0.079, 0.427, 0.233, 0.801, 0.163])
    else:
        actions = np.array([0.0, -0.173, -0.024, 2.506, -0.82, 0.029, -1.302, 0.009, -1.243, 0.057, -1.264, -1.961])

    if obs[-1] < -0.275:  # Performance adjustment
        actions *= -1.29
    elif obs[-1] > 1.442:
        actions *= -1.893

    # Minimal noise addition for fine-tuning
    actions += np.random.normal(scale=0.04, size=12)

    return actions
