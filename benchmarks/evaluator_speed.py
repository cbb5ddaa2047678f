"""Evaluator speed, measured side by side in one run (machines are noisy: compare ratios).

For each task: steps/s of colmo's fast evaluator (the exact code path the sandbox workers run)
against the plain `dm_control.suite` loop with the same policy (dm_control tasks) or a plain
`mujoco` + Python loop (A1), and against the physics floor (bare `mujoco.mj_step`, no policy,
no observation). Then where one evaluator step goes: policy call, observation, physics.
Rounds alternate between the loops and the median of each is reported.

    python benchmarks/evaluator_speed.py                  # all tasks
    python benchmarks/evaluator_speed.py --tasks pendulum --steps 3000 --rounds 5
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path
from typing import Callable

import mujoco
import numpy as np

from colmo.program import parametrize
from colmo.rollout import as_action
from colmo.sandbox.namespace import load_policy
from colmo.specs import load_spec

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"

# task -> (representative policy: the paper's Fig. 5 policy for it, dm_control (domain, task) or None)
TASKS = {
    "pendulum": ("paper_pendulum.py", ("pendulum", "swingup")),
    "ball_in_cup": ("paper_ball_in_cup.py", ("ball_in_cup", "catch")),
    "cheetah": ("paper_cheetah.py", ("cheetah", "run")),
    "quadruped": ("paper_quadruped.py", ("quadruped", "run")),
    "a1": ("paper_a1.py", None),
}


def paper_policy(task: str) -> Callable:
    """The paper's policy for `task`, loaded in this process (it is the paper's code, trusted)."""
    spec = load_spec(f"{task}.py")
    program = parametrize((EXAMPLES / TASKS[task][0]).read_text())
    return load_policy(program.skeleton, spec.allowed_imports, program.values)


def steps_per_second(run: Callable[[int], None], steps: int) -> float:
    start = time.perf_counter()
    run(steps)
    return steps / (time.perf_counter() - start)


def colmo_loop(env, policy) -> Callable[[int], None]:
    def run(steps: int) -> None:
        obs = env.reset(0)
        for step in range(steps):
            if step and step % env.horizon == 0:
                obs = env.reset(step)
            _, obs = env.step(as_action(policy(obs), env.action_size))

    return run


def dm_control_loop(domain_task: tuple[str, str], policy) -> Callable[[int], None]:
    from dm_control import suite

    env = suite.load(*domain_task, task_kwargs={"random": 0})

    def run(steps: int) -> None:
        timestep = env.reset()
        for _ in range(steps):
            if timestep.last():
                timestep = env.reset()
            obs = np.concatenate([np.asarray(v, dtype=float).ravel() for v in timestep.observation.values()])
            timestep = env.step(policy(obs))

    return run


def plain_mujoco_loop(env, policy) -> Callable[[int], None]:
    """What a user would write by hand for A1: named accessors and mj_step each control step."""
    model, data = env.model, mujoco.MjData(env.model)
    joints = [model.joint(i).name for i in range(model.njnt) if model.jnt_type[i] != mujoco.mjtJoint.mjJNT_FREE]

    def run(steps: int) -> None:
        mujoco.mj_resetDataKeyframe(model, data, 0)
        for _ in range(steps):
            angles = np.array([data.joint(name).qpos[0] for name in joints])
            velocities = np.array([data.joint(name).qvel[0] for name in joints])
            rotation = data.body("trunk").xmat.reshape(3, 3)
            velocity = rotation.T @ data.joint(0).qvel[:3]  # the free joint: trunk linear velocity
            data.ctrl[:] = np.asarray(policy(np.concatenate([angles, velocities, velocity])))
            mujoco.mj_step(model, data, env.n_sub_steps)

    return run


def physics_floor(env) -> Callable[[int], None]:
    data = mujoco.MjData(env.model)

    def run(steps: int) -> None:
        for _ in range(steps):
            mujoco.mj_step(env.model, data, env.n_sub_steps)

    return run


def breakdown(env, policy, steps: int) -> dict[str, float]:
    """Microseconds per step spent in the policy call, the observation, and the physics."""
    obs = env.reset(0)
    action = as_action(policy(obs), env.action_size)

    def timed(fn: Callable[[], object]) -> float:
        start = time.perf_counter()
        for _ in range(steps):
            fn()
        return (time.perf_counter() - start) / steps * 1e6

    policy_us = timed(lambda: as_action(policy(obs), env.action_size))
    observation_us = timed(env.observation)
    step_us = timed(lambda: env.step(action))
    return {"policy": policy_us, "observation": observation_us, "physics+reward": step_us - observation_us}


def benchmark(task: str, steps: int, rounds: int) -> None:
    env = load_spec(f"{task}.py").make_environment()
    policy = paper_policy(task)
    loops = {"colmo": colmo_loop(env, policy), "floor": physics_floor(env)}
    domain_task = TASKS[task][1]
    baseline = "dm_control" if domain_task else "plain mujoco"
    loops[baseline] = dm_control_loop(domain_task, policy) if domain_task else plain_mujoco_loop(env, policy)
    rates: dict[str, list[float]] = {name: [] for name in loops}
    for _ in range(rounds):
        for name, run in loops.items():
            rates[name].append(steps_per_second(run, steps))
    median = {name: statistics.median(values) for name, values in rates.items()}
    parts = breakdown(env, policy, steps)
    print(
        f"{task:12s} colmo {median['colmo']:9.0f} steps/s | {baseline} {median[baseline]:9.0f} steps/s | "
        f"ratio {median['colmo'] / median[baseline]:5.2f}x | floor {median['floor']:9.0f} steps/s "
        f"(colmo reaches {median['colmo'] / median['floor']:.0%}) | per step: policy {parts['policy']:.1f} us, "
        f"observation {parts['observation']:.1f} us, physics+reward {parts['physics+reward']:.1f} us"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tasks", default=",".join(TASKS), help="comma-separated task names")
    parser.add_argument("--steps", type=int, default=2000, help="control steps per measurement")
    parser.add_argument("--rounds", type=int, default=3, help="alternating rounds; medians are reported")
    args = parser.parse_args()
    for task in args.tasks.split(","):
        benchmark(task, args.steps, args.rounds)


if __name__ == "__main__":
    main()
