"""The Unitree A1 quadruped from MuJoCo Menagerie, walking backward (the paper's A1 task)."""

from __future__ import annotations

import mujoco
import mujoco_menagerie
import numpy as np

from colmo.environments.base import MujocoEnvironment

_TIMESTEP = 0.001  # s; the paper's 1 ms control period, one physics step per action
_JOINT_NOISE = 0.05  # rad; half-width of the uniform noise added to the home joint angles
_SPEED_SCALE = 10.0  # reward is clip(-v / 10, 0, 1)
# The trunk's free joint comes first (qpos 0:7, qvel 0:6: its origin's world-frame linear
# velocity, then angular), then the 12 leg hinges in servo order.
_JOINTS_QPOS = slice(7, 19)
_JOINTS_QVEL = slice(6, 18)


def a1_model() -> mujoco.MjModel:
    """Menagerie's A1 scene (robot plus floor), found through `mujoco_menagerie`.

    `mujoco_menagerie` reads the folder `MENAGERIE_ROOT` names, else its download cache
    (downloading on first use). A copy stripped of the visual meshes works too: they take no
    part in contacts and every body's inertia is given explicitly.
    """
    try:
        path = mujoco_menagerie.get("unitree_a1").xml("scene")
    except mujoco_menagerie.MenagerieError as error:
        raise FileNotFoundError(
            f"Unitree A1 model not found ({error}); set MENAGERIE_ROOT to a MuJoCo Menagerie folder holding unitree_a1/"
        ) from None
    try:
        return mujoco.MjModel.from_xml_path(str(path))
    except ValueError as error:  # MuJoCo's compile error, e.g. a mesh file missing from the copy
        raise RuntimeError(f"cannot compile {path}: {error}".replace("\n", " ")) from None


class UnitreeA1(MujocoEnvironment):
    """Unitree A1 on a flat floor, 12 position servos (kp 100), 1 ms control period.

    Observation (27): joint angles (12), joint velocities (12), trunk linear velocity in the trunk
    frame (3: forward, left, up). Joints and actions are ordered FR, FL, RR, RL legs, each
    hip (abduction), thigh, calf. Action (12): joint angle targets, clipped to the actuator
    ranges (hip ±0.80, thigh [-1.05, 4.19], calf [-2.70, -0.92] rad).
    Reward `clip(-v / 10, 0, 1)` with `v` the trunk's forward velocity: the paper's A1 walks
    backward. Episodes start at Menagerie's `home` standing keyframe with uniform noise of
    ±0.05 rad added to each joint angle (zero velocity); the physics timestep is set to 1 ms.
    """

    max_abs_reward = 1.0  # rewards lie in [0, 1]
    observation_size = 27

    def __init__(self, horizon: int = 1000):
        model = a1_model()
        model.opt.timestep = _TIMESTEP
        super().__init__(model, n_sub_steps=1, horizon=horizon)
        self._home = model.key("home").id
        if list(model.jnt_qposadr[model.actuator_trnid[:, 0]]) != list(range(_JOINTS_QPOS.start, _JOINTS_QPOS.stop)):
            raise ValueError("unexpected Unitree A1 model: the servos do not drive qpos[7:19] in order")
        self._trunk = model.body("trunk").id

    def initialize_episode(self, random: np.random.RandomState) -> None:
        mujoco.mj_resetDataKeyframe(self.model, self.data, self._home)
        self.data.qpos[_JOINTS_QPOS] += random.uniform(-_JOINT_NOISE, _JOINT_NOISE, size=self.action_size)

    def body_velocity(self) -> np.ndarray:
        """Trunk linear velocity in the trunk frame: R^T v, computed as v R."""
        return self.data.qvel[0:3] @ self.data.xmat[self._trunk].reshape(3, 3)

    def observation(self) -> np.ndarray:
        data = self.data
        return np.concatenate((data.qpos[_JOINTS_QPOS], data.qvel[_JOINTS_QVEL], self.body_velocity()))

    def reward(self) -> float:
        return float(min(max(-self.body_velocity()[0] / _SPEED_SCALE, 0.0), 1.0))
