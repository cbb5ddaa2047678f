import numpy as np


def policy(obs):
    """obs size is 27: position and angles (19), velocities (8). return shape is (12,)"""

    joint_angles = obs[0:12]
    joint_velocities = obs[12:24]
    body_velocity = obs[24:27]

    target_joint_angles = joint_angles.copy()

    # Adjust the hip joints
    target_joint_angles[0::3] += -27.697 * np.sign(body_velocity[0])
    target_joint_angles[1::3] += -6.726 * np.sign(body_velocity[0])

    # Adjust the knee joints
    target_joint_angles[1::3] += 6.09 * joint_velocities[1::3]

    # Adjusting the shoulder joints
    target_joint_angles[2::3] += -14.423

    # Add a simple spring-like mechanism
    balance_factor = 17.69
    target_joint_angles[0::3] += balance_factor * (body_velocity[1] + body_velocity[2])
    target_joint_angles[1::3] += balance_factor * (body_velocity[1] - body_velocity[2])

    # Add additional balancing adjustments
    if body_velocity[2] < -32.662:
        target_joint_angles[0::3] += 10.462
        target_joint_angles[1::3] += -22.429

    # Adjustments to ensure proper leg movement
    target_joint_angles[0::3] += 14.31
    target_joint_angles[1::3] -= -49.337

    # Return the target joint angles
    return target_joint_angles
