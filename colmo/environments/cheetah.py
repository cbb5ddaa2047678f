"""dm_control's cheetah (run) on the fast evaluator."""

from __future__ import annotations

import mujoco
import numpy as np

from colmo.environments import dm_control_model
from colmo.environments.base import MujocoEnvironment

_RUN_SPEED = 10.0  # m/s; dm_control's run speed, above which the reward is 1
_SETTLE_STEPS = 200  # physics steps dm_control runs at reset to let the cheetah land


class Cheetah(MujocoEnvironment):
    """Planar cheetah: a torso on x/z slides and a pitch hinge, with two 3-joint legs.

    Observation (17): position (8) = `qpos[1:]`, that is `[rootz, rooty, bthigh, bshin, bfoot,
    fthigh, fshin, ffoot]` (dm_control drops the root x for translation invariance), then
    velocity (9) = `qvel`, `[rootx, rootz, rooty, bthigh, ..., ffoot]`. Action (6): torques on
    `[bthigh, bshin, bfoot, fthigh, fshin, ffoot]` in [-1, 1]. 10 ms control period (dm_control's
    default: one physics step). Reward `clip(v / 10, 0, 1)` with `v` the torso subtree's forward
    velocity, which is dm_control's run reward; it is computed with dm_control's arithmetic
    (`1 - (10 - v) / 10`), so it matches dm_control bit for bit and `v / 10` to within 1e-15.
    """

    max_abs_reward = 1.0  # rewards lie in [0, 1]
    observation_size = 17

    def __init__(self, horizon: int = 1000):
        model = dm_control_model("cheetah")
        super().__init__(model, n_sub_steps=1, horizon=horizon)
        self._limited = model.jnt_limited == 1
        self._lower, self._upper = model.jnt_range[self._limited].T
        self._speed = model.sensor_adr[model.sensor("torso_subtreelinvel").id]

    def initialize_episode(self, random: np.random.RandomState) -> None:
        # As dm_control: joints uniform within their limits (every cheetah joint has one dof),
        # then 200 steps of dm_control's legacy step with zero control, clock reset to 0.
        self.data.qpos[self._limited] = random.uniform(self._lower, self._upper)
        mujoco.mj_step2(self.model, self.data)
        mujoco.mj_step(self.model, self.data, _SETTLE_STEPS - 1)
        mujoco.mj_step1(self.model, self.data)
        self.data.time = 0.0

    def observation(self) -> np.ndarray:
        return np.concatenate((self.data.qpos[1:], self.data.qvel))

    def speed(self) -> float:
        """Forward velocity of the torso subtree's centre of mass (dm_control's `speed()`)."""
        return float(self.data.sensordata[self._speed])

    def reward(self) -> float:
        speed = self.speed()
        if speed >= _RUN_SPEED:
            return 1.0
        return max(1.0 - (_RUN_SPEED - speed) / _RUN_SPEED, 0.0)
