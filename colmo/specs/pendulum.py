"""Pendulum swing-up.

An input-constrained pendulum hangs from a hinge. The maximum torque is one sixth of what
would lift it from the horizontal at rest, so the policy must pump energy into the swing
before it can bring the pole upright and balance it there.

Observation (size 3): [cos(theta), sin(theta), angular velocity], where theta is the pole's
angle from upright (theta = 0 is upright). Action: one torque in [-1, 1] (values outside are
clipped). Control period 20 ms, episodes of 1000 steps. Reward: 1 for every step with
|theta| < 0.5 rad, 0 otherwise. The initial angle is uniformly random.
"""


from colmo.environments.pendulum import PendulumSwingup

OBSERVATION_NAMES = (
    "cos_theta",
    "sin_theta",
    "angular_velocity",
)
OBSERVATION_BOUNDS = ((-1.0, 1.0), (-1.0, 1.0), None)  # a cosine and a sine; the velocity has no bound


def make_environment(**options) -> PendulumSwingup:
    return PendulumSwingup(**options)


def policy(obs):
    """obs size is 3. return shape is ()."""
    action = 0.0
    return action
