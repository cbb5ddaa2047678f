"""`python -m colmo.render task=... policy_file=... [out=DIR] [seed=0] [episode=0] [steps=N]`.

Writes `episode.png` (observations, actions, cumulative reward) and `episode.mp4` (or `.gif`)
of one held-out episode of a policy file, the same episodes `colmo-evaluate` scores (`seed`,
`episode`: which one), recorded by the referee in the sandbox. The files go to `out`, which
must not already hold them (nothing is overwritten), or by default to the run's own new
directory (`outputs/render/...`). Without OpenGL it says so in one line, writes the plot and
exits 0; a policy that fails in the episode exits 1. The last stdout line is a JSON object:
`video` (a path or null), `plot`, `episode_return`, `episode_seed`, `seconds`, `note`, ...
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

from omegaconf import MISSING

from colmo.cli import SCHEMAS, hydra_app
from colmo.config import ExecutorConfig, TaskConfig, option
from colmo.errors import ConfigError
from colmo.intake import read_policy_file
from colmo.render import PLOT_FILE, VIDEO_FILE, render_policy
from colmo.specs import load_task_spec


@dataclass
class RenderConfig:
    """`python -m colmo.render`: a video and a plot of one held-out episode of a policy file."""

    task: TaskConfig = MISSING
    executor: ExecutorConfig = MISSING
    policy_file: str = option(MISSING, "a .py file with `def policy(obs)`, or a raw language-model answer")
    out: Optional[str] = option(None, "directory for episode.png and episode.mp4 (must not hold them yet); null: the run directory")
    seed: int = option(0, "the run seed whose held-out episodes are used (as colmo-evaluate)")
    episode: int = option(0, "which held-out episode: 0 is the first that colmo-evaluate scores")
    steps: Optional[int] = option(None, "cut the episode to this many control steps; null: the whole episode")
    width: int = option(640, "video width in pixels (even)")
    height: int = option(480, "video height in pixels (even)")

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            size = getattr(self, name)
            if size < 2 or size % 2:
                raise ConfigError(f"{name} must be even and >= 2 (H.264 needs it), got {size}")
        if self.episode < 0:
            raise ConfigError(f"episode must be >= 0, got {self.episode}")
        if self.steps is not None and self.steps < 1:
            raise ConfigError(f"steps must be >= 1 or null, got {self.steps}")


SCHEMAS[(None, "render_schema")] = RenderConfig


def check_inputs(cfg: RenderConfig) -> None:
    """The policy file is usable, `out` holds no earlier episode files, `steps` fits the task."""
    spec = load_task_spec(cfg.task.spec)
    read_policy_file(cfg.policy_file, spec.allowed_imports)
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
    from hydra.core.hydra_config import HydraConfig

    from colmo.evaluate import heldout_evaluator, task_evaluator
    from colmo.executor import make_executor

    directory = Path(cfg.out).expanduser() if cfg.out else Path(HydraConfig.get().runtime.output_dir)
    executor = make_executor(cfg.executor, max_workers=1)  # requests run one at a time here
    try:
        spec, evaluator = task_evaluator(cfg.task, cfg.executor, executor, cfg.seed)
        program = read_policy_file(cfg.policy_file, spec.allowed_imports)
        heldout = heldout_evaluator(evaluator, cfg.seed, cfg.episode + 1)
        title = f"{cfg.task.name}: {Path(cfg.policy_file).name}, held-out"
        media = render_policy(
            executor, heldout, program.skeleton, program.values, directory, title,
            episode=cfg.episode, steps=cfg.steps, width=cfg.width, height=cfg.height,
        )
    finally:
        executor.close()
    for label, path in (("plot", media.plot), ("video", media.video)):
        if path is not None:
            print(f"{label}: {path}")
    if media.note:
        print(media.note)
    print(json.dumps({"task": cfg.task.name, "policy_file": cfg.policy_file, "seed": cfg.seed, "episode": cfg.episode, **media.as_dict()}))
    if media.plot is None:
        sys.exit(1)


if __name__ == "__main__":
    main()
