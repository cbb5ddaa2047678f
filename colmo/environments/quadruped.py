"""dm_control's quadruped (run) on the fast evaluator, with the paper's or dm_control's reward."""

from __future__ import annotations

import importlib.resources
import xml.etree.ElementTree as ElementTree

import mujoco
import numpy as np

from colmo.environments.base import MujocoEnvironment

_CONTROL_TIMESTEP = 0.02  # dm_control's quadruped control period, in seconds
_RUN_SPEED = 5.0  # dm_control's run speed (m/s), above which its move reward is 1
_PAPER_SPEED = 10.0  # the paper's reward is clip(v / 10, 0, 1)
_FLOOR_SIZE = 100  # dm_control's run floor: time limit (20 s) times run speed
_MAX_HEIGHT_ATTEMPTS = 10000


def run_model() -> mujoco.MjModel:
    """The model of dm_control's `quadruped.run`, as its `make_model(floor_size=100)` edits it.

    The floor is enlarged and the walls, ball, target, terrain and rangefinders are removed.
    """
    suite = importlib.resources.files("dm_control") / "suite"
    root = ElementTree.fromstring((suite / "quadruped.xml").read_text())
    parents = {child: parent for parent in root.iter() for child in parent}

    def remove(tag: str, name: str) -> None:
        element = root.find(f".//{tag}[@name='{name}']")
        parents[element].remove(element)

    root.find(".//geom[@name='floor']").set("size", f"{_FLOOR_SIZE} {_FLOOR_SIZE} .5")
    for wall in ("wall_px", "wall_py", "wall_nx", "wall_ny"):
        remove("geom", wall)
    remove("body", "ball")
    remove("site", "target")
    remove("geom", "terrain")
    for rangefinder in root.findall(".//rangefinder"):
        parents[rangefinder].remove(rangefinder)
    assets = {
        entry.name: entry.read_bytes()
        for entry in (suite / "common").iterdir()
        if entry.name.endswith((".xml", ".png"))
    }
    return mujoco.MjModel.from_xml_string(ElementTree.tostring(root, encoding="unicode"), assets)


def _span(indices: np.ndarray) -> slice:
    """The slice of consecutive `indices` (slicing is cheaper than indexing with an array)."""
    first = int(indices[0])
    if not np.array_equal(indices, np.arange(first, first + len(indices))):
        raise ValueError(f"expected consecutive indices, got {indices}")
    return slice(first, first + len(indices))


def _sensor_span(model: mujoco.MjModel, *types: mujoco.mjtSensor) -> slice:
    """Where the sensors of the given types sit in `sensordata`, in sensor order (as dm_control)."""
    ids = np.flatnonzero(np.isin(model.sensor_type, [int(t) for t in types]))
    return _span(np.concatenate([model.sensor_adr[i] + np.arange(model.sensor_dim[i]) for i in ids]))


class Quadruped(MujocoEnvironment):
    """dm_control's ant-like quadruped: 4 legs with yaw, hip, knee and ankle hinges, on a flat floor.

    Observation (78), dm_control's `_common_observations` flattened in order:
    egocentric_state (44) = 16 hinge angles, 16 hinge velocities, 12 actuator activations;
    torso_velocity (3, velocimeter, torso frame); torso_upright (1, torso z-axis · world z);
    imu (6) = accelerometer (3), gyro (3); force_torque (24) = arcsinh of the 4 toe force
    sensors (3 each) then the 4 toe torque sensors (3 each).
    Action (12): position-servo targets (yaw, lift, extend per leg, legs front-left,
    front-right, back-right, back-left), each clipped to its actuator's range. 20 ms control period.

    `start="upright"` (default): each episode starts with the torso level, facing forward, at the
    lowest height where nothing touches the floor, as the paper's published policy needs (it
    runs from there in every episode, 189 over 10, the paper's 181.3; from random orientations it
    runs in 3 of 10). `start="random"`: dm_control's uniformly random orientation.
    `joint_noise` (radians, default 0): each hinge angle starts off its rest angle by a uniform
    draw from [-joint_noise, joint_noise] (the A1's start has ±0.05), so that upright episodes
    differ from each other; 0 draws nothing, and every episode from upright is the same.

    `reward="paper"` (default): `clip(v / 10, 0, 1)` with `v` the torso's forward velocity
    (velocimeter x, torso frame), the paper's locomotion reward. `reward="dm_control"`:
    dm_control's run reward, an uprightness factor times a move term that is 1 above 5 m/s and
    0.5 at standstill, computed with dm_control's arithmetic so that it matches it exactly.
    """

    max_abs_reward = 1.0  # rewards lie in [0, 1]
    observation_size = 78

    def __init__(self, reward: str = "paper", horizon: int = 1000, start: str = "upright", joint_noise: float = 0.0):
        if reward not in ("paper", "dm_control"):
            raise ValueError(f"unknown reward {reward!r}: expected 'paper' or 'dm_control'")
        if start not in ("upright", "random"):
            raise ValueError(f"unknown start {start!r}: expected 'upright' or 'random'")
        if not 0.0 <= joint_noise <= 0.5:
            raise ValueError(f"joint_noise must be in [0, 0.5] radians, got {joint_noise!r}")
        self._random_orientation = start == "random"
        self._joint_noise = joint_noise
        model = run_model()
        super().__init__(model, n_sub_steps=round(_CONTROL_TIMESTEP / model.opt.timestep), horizon=horizon)
        self._dm_control_reward = reward == "dm_control"
        self._root_qpos = model.joint("root").qposadr[0]
        hinges = np.flatnonzero(model.jnt_type == mujoco.mjtJoint.mjJNT_HINGE)
        sensors = mujoco.mjtSensor
        self._hinge_qpos = _span(model.jnt_qposadr[hinges])
        self._hinge_qvel = _span(model.jnt_dofadr[hinges])
        self._torso_velocity = _sensor_span(model, sensors.mjSENS_VELOCIMETER)
        self._torso = model.body("torso").id
        self._imu = _sensor_span(model, sensors.mjSENS_GYRO, sensors.mjSENS_ACCELEROMETER)
        self._force_torque = _sensor_span(model, sensors.mjSENS_FORCE, sensors.mjSENS_TORQUE)

    def initialize_episode(self, random: np.random.RandomState) -> None:
        # dm_control's `_find_non_contacting_height`: the orientation (uniformly random in
        # dm_control), then the lowest height (1 cm steps from 0) at which nothing touches the torso or legs.
        if self._random_orientation:
            orientation = random.randn(4)
            orientation /= np.linalg.norm(orientation)
        else:
            orientation = np.array([1.0, 0.0, 0.0, 0.0])
        hinges = self.model.qpos0[self._hinge_qpos].copy()
        if self._joint_noise:
            hinges += random.uniform(-self._joint_noise, self._joint_noise, size=hinges.size)
        height = self._lowest_free_height(orientation, hinges)
        # dm_control runs every try as reset, unactuated forward, place, unactuated forward.
        # Each starts from mj_resetData, so only the last one shapes the state: replay it alone.
        mujoco.mj_resetData(self.model, self.data)
        self.forward_unactuated()
        self._place_root(height, orientation, hinges)
        self.forward_unactuated()

    def _place_root(self, height: float, orientation: np.ndarray, hinges: np.ndarray) -> None:
        root = self._root_qpos
        self.data.qpos[root : root + 3] = 0.0, 0.0, height
        self.data.qpos[root + 3 : root + 7] = orientation
        self.data.qpos[self._hinge_qpos] = hinges

    def _lowest_free_height(self, orientation: np.ndarray, hinges: np.ndarray) -> float:
        """dm_control's search, with collision detection alone (the contacts are all it reads)."""
        height = 0.0
        for _ in range(_MAX_HEIGHT_ATTEMPTS + 1):
            self._place_root(height, orientation, hinges)
            mujoco.mj_kinematics(self.model, self.data)
            mujoco.mj_collision(self.model, self.data)
            if self.data.ncon == 0:
                return height
            height += 0.01  # accumulated, not multiplied, to land on dm_control's exact heights
        raise RuntimeError("Failed to find a non-contacting configuration.")

    def observation(self) -> np.ndarray:
        data = self.data
        sensors = data.sensordata
        return np.concatenate(
            (
                data.qpos[self._hinge_qpos],
                data.qvel[self._hinge_qvel],
                data.act,
                sensors[self._torso_velocity],
                data.xmat[self._torso, 8:9],  # torso_upright: zz of the torso frame
                sensors[self._imu],
                np.arcsinh(sensors[self._force_torque]),
            )
        )

    def reward(self) -> float:
        speed = self.data.sensordata[self._torso_velocity.start]
        if not self._dm_control_reward:
            return float(min(max(speed / _PAPER_SPEED, 0.0), 1.0))
        # dm_control's rewards.tolerance with a linear sigmoid, written out with its operations.
        upright = self.data.xmat[self._torso, 8]
        upright_reward = 1.0 if upright >= 1.0 else max(1.0 - (1.0 - upright) / 2.0, 0.0)
        move_reward = 1.0 if speed >= _RUN_SPEED else max(1.0 - (_RUN_SPEED - speed) / _RUN_SPEED * 0.5, 0.0)
        return float(upright_reward * move_reward)
