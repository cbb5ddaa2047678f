"""`colmo-render task=... policy_file=... [out=DIR] [seed=0] [episode=0] [steps=N]` (or `python -m colmo.render`).

Writes `episode.png` (observations, actions, cumulative reward) and `episode.mp4` (or `.gif`)
of one held-out episode of a policy file, the same episodes `colmo-evaluate` scores (`seed`,
`episode`: which one), recorded by the referee in the sandbox. The files go to `out`, which
must not already hold them (nothing is overwritten), or by default to the run's own new
directory (`outputs/render/...`). Without OpenGL it says so in one line, writes the plot and
exits 0; a policy that fails in the episode exits 1. The last stdout line is a JSON object:
`video` (a path or null), `plot`, `episode_return`, `episode_seed`, `seconds`, `note`, ...
"""

from __future__ import annotations

import sys
from pathlib import Path

from colmo.cli import hydra_app
from colmo.config import RenderConfig
from colmo.errors import ConfigError
from colmo.policy_tools import check_policy_file, policy_session, print_result, run_directory
from colmo.render import PLOT_FILE, VIDEO_FILE, render_policy


def check_inputs(cfg: RenderConfig) -> None:
    """The policy file is usable, `out` holds no earlier episode files, `steps` fits the task."""
    spec = check_policy_file(cfg)
    if cfg.out:
        out = Path(cfg.out).expanduser()
        if out.exists() and not out.is_dir():
            raise ConfigError(f"out is not a directory: {cfg.out}")
        for name in (PLOT_FILE, VIDEO_FILE, Path(VIDEO_FILE).with_suffix(".gif").name):
            if (out / name).exists():
                raise ConfigError(f"out={cfg.out} already holds {name}: choose a new directory (nothing is overwritten)")
    if cfg.steps is not None:
        horizon = spec.make_environment(**cfg.task.env).horizon
        if cfg.steps > horizon:
            raise ConfigError(f"steps={cfg.steps} is more than the task's {horizon} control steps")


@hydra_app("render", check=check_inputs)
def main(cfg: RenderConfig) -> None:
    """Write a video and a plot of one held-out episode of a policy file, recorded by the referee."""
    directory = Path(cfg.out).expanduser() if cfg.out else run_directory()
    with policy_session(cfg, max_workers=1) as session:  # requests run one at a time here
        title = f"{cfg.task.name}: {Path(cfg.policy_file).name}, held-out"
        media = render_policy(
            session.executor, session.heldout(cfg.episode + 1), session.program.skeleton, session.program.values, directory, title,
            episode=cfg.episode, steps=cfg.steps, width=cfg.width, height=cfg.height,
        )
    for label, path in (("plot", media.plot), ("video", media.video)):
        if path is not None:
            print(f"{label}: {path}")
    if media.note:
        print(media.note)
    print_result({"task": cfg.task.name, "policy_file": cfg.policy_file, "seed": cfg.seed, "episode": cfg.episode, **media.as_dict()})
    if media.plot is None:
        sys.exit(1)


if __name__ == "__main__":
    main()
