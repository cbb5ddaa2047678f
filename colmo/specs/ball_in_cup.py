"""Ball in cup (catch).

A planar system in the vertical x-z plane: a cup moves on two actuated slides (horizontal x,
vertical z), and a ball hangs from the bottom of the cup on a 0.3 m string (the string can go
slack but not stretch). Each slide has a spring pulling the cup back to its rest position and
damping, so a constant action a holds the cup roughly 0.25 * a m away from rest: the actions
act like reference positions tracked by a low-level linear controller. The policy must swing
the ball up and catch it in the cup.

Observation (size 8): position (4) then velocity (4).
- obs[0], obs[1]: cup displacement from its rest position, horizontal and vertical (m, z up).
  The cup is 0.1 m wide and 0.1 m deep; its rim centre is at x = obs[0], height 0.6 + obs[1].
- obs[2], obs[3]: ball position: x = obs[2], height 0.5 + obs[3] (m). Ball radius 0.025 m.
- obs[4:8]: the time derivatives of obs[0:4] (m/s), same order.
The ball is in the cup when |ball x - cup x| < 0.025 and |(0.5 + obs[3]) - (0.55 + obs[1])| < 0.025,
that is when obs[3] - obs[1] is close to 0.05 and obs[2] - obs[0] is close to 0.
Action (shape (2,)): horizontal and vertical force commands for the cup, each in [-1, 1]
(values outside are clipped). Control period 20 ms, episodes of 1000 steps. Reward: 1 for every
step the ball is inside the cup, 0 otherwise. The ball starts at a random position, at rest.
"""

import numpy as np

from colmo.environments.ball_in_cup import BallInCup

OBSERVATION_NAMES = (
    "cup_x",
    "cup_z",
    "ball_x",
    "ball_z",
    "cup_x_velocity",
    "cup_z_velocity",
    "ball_x_velocity",
    "ball_z_velocity",
)


def make_environment(**options) -> BallInCup:
    return BallInCup(**options)


def policy(obs):
    """obs size is 8: position (4), velocity (4). return shape is (2,)."""
    action = np.zeros(2)
    return action
