"""Cheetah run.

A planar two-legged "cheetah" (total mass 14 kg) moving in the vertical x-z plane: a torso
that can slide forward (x) and up (z) and pitch, with a back leg and a front leg of three hinge
joints each (thigh, shin, foot). Each joint has a spring toward its rest angle and damping, and
is driven by a torque motor. The goal is to run forward as fast as possible.

Observation (size 17): position (8) then velocity (9).
- obs[0]: torso height relative to its initial 0.7 m (m); obs[1]: torso pitch angle (rad).
- obs[2:5]: back thigh, back shin, back foot joint angles (rad).
- obs[5:8]: front thigh, front shin, front foot joint angles (rad).
- obs[8]: forward velocity of the torso (m/s); obs[9]: vertical velocity (m/s);
  obs[10]: pitch angular velocity (rad/s).
- obs[11:17]: angular velocities of the six leg joints (rad/s), same order as obs[2:8].
The forward position is not observed.
Action (shape (6,)): torques for back thigh, back shin, back foot, front thigh, front shin,
front foot, each in [-1, 1] (values outside are clipped), scaled by motor gears of
120, 90, 60, 90, 60, 30 N*m. Control period 10 ms, episodes of 1000 steps. Reward per step:
clip(v / 10, 0, 1) with v the forward velocity (m/s) of the cheetah's centre of mass.
Episodes start with random joint angles, after the cheetah has been left to settle for 2 s.
"""

import numpy as np

from colmo.environments.cheetah import Cheetah

OBSERVATION_NAMES = (
    "torso_height",
    "torso_pitch",
    "back_thigh_angle",
    "back_shin_angle",
    "back_foot_angle",
    "front_thigh_angle",
    "front_shin_angle",
    "front_foot_angle",
    "forward_velocity",
    "vertical_velocity",
    "pitch_velocity",
    "back_thigh_velocity",
    "back_shin_velocity",
    "back_foot_velocity",
    "front_thigh_velocity",
    "front_shin_velocity",
    "front_foot_velocity",
)


def make_environment(**options) -> Cheetah:
    return Cheetah(**options)


def policy(obs):
    """obs size is 17: position (8), velocity (9). return shape is (6,)."""
    action = np.zeros(6)
    return action
