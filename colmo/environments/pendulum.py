"""dm_control's pendulum (swingup) on the fast evaluator, with the paper's reward."""

from __future__ import annotations

import math

import numpy as np

from colmo.environments import dm_control_model
from colmo.environments.base import MujocoEnvironment


class PendulumSwingup(MujocoEnvironment):
    """Observation `[cos θ, sin θ, θ̇]` (dm_control's order), one torque in [-1, 1], 20 ms steps.

    Reward 1 while the pole is within `angle_bound` radians of upright. The paper uses 0.5 rad;
    dm_control's own swingup task uses 8 degrees (`angle_bound=math.radians(8)` reproduces it).
    """

    max_abs_reward = 1.0  # rewards lie in [0, 1]
    observation_size = 3

    def __init__(self, angle_bound: float = 0.5, horizon: int = 1000):
        super().__init__(dm_control_model("pendulum"), n_sub_steps=1, horizon=horizon)
        self.cosine_bound = math.cos(angle_bound)
        self._hinge_qpos = self.model.joint("hinge").qposadr[0]
        self._hinge_qvel = self.model.joint("hinge").dofadr[0]
        # Views into `self.data`, which lives as long as the environment (a reset copies into it):
        # taken once, since reading them anew cost a third of a step's Python.
        self._pole_xmat = self.data.xmat[self.model.body("pole").id]
        self._qvel = self.data.qvel

    def initialize_episode(self, random: np.random.RandomState) -> None:
        self.data.qpos[self._hinge_qpos] = random.uniform(-np.pi, np.pi)

    def observation(self) -> np.ndarray:
        xmat = self._pole_xmat
        return np.array((xmat[8], xmat[2], self._qvel[self._hinge_qvel]))  # zz, xz as dm_control

    def reward(self) -> float:
        return 1.0 if self._pole_xmat[8] >= self.cosine_bound else 0.0
