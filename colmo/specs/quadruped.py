"""Quadruped run.

A three-dimensional four-legged robot (about 107 kg, torso mass 68 kg) on a flat floor. Each leg
has four hinge joints: yaw (swings the leg around the vertical torso axis), hip pitch, knee and
ankle, ending in a toe. Each leg is driven by three position servos: a yaw servo on the yaw
joint, and "lift" and "extend" servos that act on combinations of the pitch, knee and ankle
angles (lift = (pitch - ankle) / 2 raises the foot, extend = pitch / 4 - knee / 2 + ankle / 4
stretches the leg). Each servo's target follows the commanded action through a first-order
filter with a 0.1 s time constant. The goal is to run forward, in the torso's facing direction,
as fast as possible. Episodes start with the torso upright and level, facing forward, just
above the floor.

Observation (size 78). Legs are ordered front-left, front-right, back-right, back-left.
- obs[0:16]: joint angles (rad), per leg yaw, pitch, knee, ankle.
- obs[16:32]: joint angular velocities (rad/s), same order.
- obs[32:44]: the 12 servo targets after filtering (same order as the actions).
- obs[44:47]: torso linear velocity in the torso frame (m/s): forward, left, up.
- obs[47]: torso uprightness: cosine of the angle between the torso's up axis and the
  vertical (1 upright, -1 upside down).
- obs[48:54]: IMU in the torso frame: linear acceleration (3, m/s^2, includes gravity: about
  +9.81 along the torso's up axis at rest), then angular velocity (3, rad/s).
- obs[54:78]: arcsinh of the force (N) each of the 4 toes transmits to its leg (3 values each,
  in the toe frame; mostly the ground contact force), then arcsinh of the torque (N*m) at each
  toe (3 values each); same leg order. arcsinh(x) is about x for small x and about
  sign(x) * log(2|x|) for large x.
Action (shape (12,)): per leg (front-left, front-right, back-right, back-left) the yaw, lift
and extend servo targets, in [-1, 1], [-1, 1.1] and [-0.8, 0.8] respectively (values outside
are clipped). Control period 20 ms, episodes of 1000 steps. Reward per step: clip(v / 10, 0, 1)
with v the torso's forward velocity (m/s, obs[44]).
"""

import numpy as np

from colmo.environments.quadruped import Quadruped

# Only the uprightness, a cosine, has a bound that holds whatever the policy does.
OBSERVATION_BOUNDS = (None,) * 47 + ((-1.0, 1.0),) + (None,) * 30


def make_environment(**options) -> Quadruped:
    return Quadruped(**options)


def policy(obs):
    """obs size is 78: egocentric state (44), torso velocity (3), torso upright (1), imu (6),
    force torque (24). return shape is (12,)."""
    action = np.zeros(12)
    return action
