"""Unitree A1 walking backward.

A simulated Unitree A1 quadruped robot (MuJoCo Menagerie model, about 12 kg) on a flat floor.
Each leg has three joints: hip (abduction, swings the leg sideways), thigh (swings the leg
forward and back) and calf (knee). Every joint is driven by a position servo (stiffness
100 N*m/rad, torque limited to 33.5 N*m) that tracks the commanded joint angle. The goal is to
walk backward, opposite to the direction the robot faces, as fast as possible.

Legs are ordered front-right (FR), front-left (FL), rear-right (RR), rear-left (RL); within a
leg the joints are hip, thigh, calf.
Observation (size 27):
- obs[0:12]: joint angles (rad), FR hip, FR thigh, FR calf, FL hip, ..., RL calf.
- obs[12:24]: joint angular velocities (rad/s), same order.
- obs[24:27]: trunk linear velocity in the trunk frame (m/s): forward, left, up.
Action (shape (12,)): target joint angles (rad), same order as obs[0:12], clipped to the joint
ranges: hip [-0.80, 0.80], thigh [-1.05, 4.19], calf [-2.70, -0.92]. The standing pose is
hip 0, thigh 0.9, calf -1.8 for every leg. Control period 1 ms, episodes of 1000 steps (1 s).
Reward per step: clip(-v / 10, 0, 1) with v the trunk's forward velocity (m/s, obs[24]), so
only backward motion is rewarded. Episodes start standing, with small random joint offsets.
"""

import numpy as np

from colmo.environments.a1 import UnitreeA1


def make_environment(**options) -> UnitreeA1:
    return UnitreeA1(**options)


def policy(obs):
    """obs size is 27: joint angles (12), joint velocities (12), body velocity (3). return shape is (12,)."""
    action = np.zeros(12)
    return action
