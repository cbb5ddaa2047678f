"""What the A1's one-second episodes pay for: the trunk's height, its displacement and the return
over a longer episode, for three fixed policies (written here, not loaded: trusted code only).

    MENAGERIE_ROOT=... python scripts/a1_topple.py [--horizon 3000] [--seed 0]

- `winner`: seed 2's 30-minute winner (docs/locomotion-search/a1/default/s2/best_policy.py):
  every joint's target 0.0279 * obs[22], about 0, i.e. legs straight;
- `starter`: the spec's starter, every target 0;
- `standing`: Menagerie's standing pose held (hip 0, thigh 0.9, calf -1.8).
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
}
TIMES_S = (0.1, 0.25, 0.5, 1.0, 2.0, 3.0, 5.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--horizon", type=int, default=3000, help="control steps (1 ms each)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    print("| policy | time (s) | trunk height (m) | trunk x (m) | return so far |")
    print("|---|---|---|---|---|")
    for name, policy in POLICIES.items():
        env = UnitreeA1(horizon=args.horizon)
        obs, total = env.reset(args.seed), 0.0
        marks = {round(seconds / env.control_timestep) for seconds in TIMES_S}
        for step in range(1, args.horizon + 1):
            reward, obs = env.step(policy(obs))
            total += reward
            if step in marks:
                print(f"| {name} | {step * env.control_timestep:g} | {env.data.qpos[2]:.2f} | {env.data.qpos[0]:.2f} | {total:.1f} |")


if __name__ == "__main__":
    main()
