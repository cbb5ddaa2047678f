"""What the A1's one-second episodes pay for: the trunk's height, its displacement, whether it is
upright, and the return over a longer episode, for fixed policies (written here, not loaded:
trusted code only).

    MENAGERIE_ROOT=... python scripts/a1_topple.py [--horizon 3000] [--seed 0]   # one episode, over time
    MENAGERIE_ROOT=... python scripts/a1_topple.py --episodes 20               # episodes 0-19: returns, falls

- `winner`: seed 2's 30-minute winner (docs/locomotion-search/a1/default/s2/best_policy.py):
  every joint's target 0.0279 * obs[22], about 0, i.e. legs straight;
- `starter`: the spec's starter, every target 0;
- `standing`: Menagerie's standing pose held (hip 0, thigh 0.9, calf -1.8);
- `seconds3`: the 30-minute winner of a search on 3-second episodes
  (docs/locomotion-search/a1/seconds3/s0/best_policy.py).
"""

from __future__ import annotations

import argparse
from typing import Callable

import numpy as np

from colmo.environments.a1 import UnitreeA1

POLICIES: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "winner": lambda obs: np.zeros(12) + 0.0279 * obs[22],
    "starter": lambda obs: np.zeros(12),
    "standing": lambda obs: np.tile([0.0, 0.9, -1.8], 4),
    "seconds3": lambda obs: np.array([0.116, -0.02313, 0.06715, 1.763, 0.1363, -0.07408, 0.1047, -0.5873, 0.1669, 0.1107, 0.3571, -0.1396]) * obs[15]
    + 0.5327 * obs[4],
}
TIMES_S = (0.1, 0.25, 0.5, 1.0, 2.0, 3.0, 5.0)


def upright(env: UnitreeA1) -> float:
    """The vertical component of the trunk's up axis: 1 level, 0 on its side, -1 on its back."""
    qx, qy = env.data.qpos[4:6]  # the trunk's orientation quaternion (w, x, y, z) from qpos[3]
    return float(1 - 2 * (qx**2 + qy**2))


def episode(policy: Callable[[np.ndarray], np.ndarray], horizon: int, seed: int, times_s: tuple[float, ...] = ()) -> tuple[UnitreeA1, float, list[str]]:
    """One episode: the environment at its end, the return, and a table row at each of `times_s`."""
    env = UnitreeA1(horizon=horizon)
    marks = {round(seconds / env.control_timestep) for seconds in times_s}
    obs, total, rows = env.reset(seed), 0.0, []
    for step in range(1, horizon + 1):
        reward, obs = env.step(policy(obs))
        total += reward
        if step in marks:
            data = env.data
            rows.append(f"{step * env.control_timestep:g} | {data.qpos[2]:.2f} | {data.qpos[0]:.2f} | {upright(env):.2f} | {total:.1f}")
    return env, total, rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--horizon", type=int, default=3000, help="control steps (1 ms each)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--episodes", type=int, default=0, help="instead of one episode over time: each policy on episodes 0..N-1")
    args = parser.parse_args()
    if args.episodes:
        print(f"| policy | return over {args.horizon} steps, mean ± std | on its back at the end | trunk x at the end, mean (m) |")
        print("|---|---|---|---|")
        for name, policy in POLICIES.items():
            ends = [episode(policy, args.horizon, seed) for seed in range(args.episodes)]
            returns = np.array([total for _, total, _ in ends])
            fallen = sum(upright(env) < 0 for env, _, _ in ends)
            x = np.mean([env.data.qpos[0] for env, _, _ in ends])
            print(f"| {name} | {returns.mean():.1f} ± {returns.std(ddof=1):.1f} | {fallen} of {args.episodes} | {x:.2f} |")
        return
    print("| policy | time (s) | trunk height (m) | trunk x (m) | trunk upright (1 level, -1 on its back) | return so far |")
    print("|---|---|---|---|---|---|")
    for name, policy in POLICIES.items():
        for row in episode(policy, args.horizon, args.seed, TIMES_S)[2]:
            print(f"| {name} | {row} |")


if __name__ == "__main__":
    main()
