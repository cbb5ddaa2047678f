"""The root schemas, one per app: what each command line composes (`conf/<app>.yaml`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Optional

from omegaconf import MISSING

from colmo.config.components import ExecutorConfig, GFOConfig, TrackerConfig
from colmo.config.fields import option, require
from colmo.config.generators import GeneratorConfig, LanguageModelConfig
from colmo.config.search import DatabaseConfig, FinishConfig, HeldoutConfig, SearchLoopConfig, SimplifyConfig
from colmo.config.task import MAX_EPISODES_HELP, PRECISION_HELP, ROBUSTNESS_DELAYS, ROBUSTNESS_MAGNITUDES, TaskConfig, check_robustness_grid


@dataclass
class SearchConfig:
    """`colmo`: the program search."""

    task: TaskConfig = MISSING
    gfo: GFOConfig = MISSING
    llm: GeneratorConfig = MISSING
    database: DatabaseConfig = MISSING
    executor: ExecutorConfig = MISSING
    tracker: TrackerConfig = MISSING
    search: SearchLoopConfig = field(default_factory=SearchLoopConfig)
    heldout: HeldoutConfig = field(default_factory=HeldoutConfig)
    finish: FinishConfig = field(default_factory=FinishConfig)
    simplify: SimplifyConfig = field(default_factory=SimplifyConfig)
    seed: int = option(0, "episode seeds, prompts and optimizers derive from it")
    resume: Optional[str] = option(None, "an earlier run's directory to continue")

    def __post_init__(self) -> None:
        require(self.seed >= 0, f"seed must be >= 0, got {self.seed}")
        require(
            not (self.search.steady_state and isinstance(self.llm, LanguageModelConfig)),
            f"search.steady_state=true is for llm=mutate, whose answers take no time: with llm={self.llm.name} the workers "
            "would wait for each call (search.fill=mutate keeps them busy while the model writes)",
        )


@dataclass
class PolicyFileConfig:
    """Fields every one-file tool has (`colmo-optimize`, `-evaluate`, `-simplify`, `-render`):
    the task, where evaluations run, the policy file and the run seed."""

    task: TaskConfig = MISSING
    executor: ExecutorConfig = MISSING
    policy_file: str = option(MISSING, "a .py file with `def policy(obs)`, or a raw language-model answer")
    seed: int = option(
        0, "the run seed: the training episodes, the held-out ones (disjoint from them, the same for every tool) "
        "and the optimizer's randomness derive from it",
    )

    def __post_init__(self) -> None:
        require(self.seed >= 0, f"seed must be >= 0, got {self.seed}")


@dataclass
class OptimizeConfig(PolicyFileConfig):
    """`colmo-optimize`: tune the constants of one policy file."""

    gfo: GFOConfig = MISSING
    tracker: TrackerConfig = MISSING
    heldout: HeldoutConfig = field(default_factory=HeldoutConfig)


@dataclass
class EvaluateConfig(PolicyFileConfig):
    """`colmo-evaluate`: score a policy file on held-out episodes."""

    episodes: int = option(100, "held-out episodes")
    coverage: bool = option(
        False, "also count what each branch of the policy did over the held-out episodes (fast path) and print the policy "
        "with the counts as comments (colmo.coverage)",
    )
    robustness: bool = option(False, "also score the policy over a grid of model-mismatch magnitudes (colmo.robustness)")
    robustness_episodes: int = option(
        20, "held-out episodes per robustness grid point, the same for every point: each point's score and its change from "
        "nominal come with a 95% interval (paired over the episodes)",
    )
    robustness_precision: Optional[float] = option(None, PRECISION_HELP)
    robustness_max_episodes: int = option(320, MAX_EPISODES_HELP)
    robustness_magnitudes: list[float] = option(ROBUSTNESS_MAGNITUDES, "relative magnitudes of the robustness grid (0, nominal, is always scored)")
    robustness_delays: list[int] = option(ROBUSTNESS_DELAYS, "control delays (steps) of the robustness grid")

    def __post_init__(self) -> None:
        super().__post_init__()
        require(self.episodes >= 1, f"episodes must be >= 1, got {self.episodes}")
        check_robustness_grid(
            "", self.robustness_episodes, self.robustness_magnitudes, self.robustness_delays, self.robustness_precision, self.robustness_max_episodes,
        )


@dataclass
class SimplifyAppConfig(PolicyFileConfig):
    """`colmo-simplify`: shorten a policy file, every step measured by the referee."""

    gfo: GFOConfig = MISSING
    simplify: SimplifyConfig = field(default_factory=SimplifyConfig)
    heldout: HeldoutConfig = field(default_factory=HeldoutConfig)


@dataclass
class RenderConfig(PolicyFileConfig):
    """`colmo-render`: a video and a plot of one held-out episode of a policy file."""

    out: Optional[str] = option(None, "directory for episode.png and episode.mp4 (must not hold them yet); null: the run directory")
    episode: int = option(0, "which held-out episode: 0 is the first that colmo-evaluate scores")
    steps: Optional[int] = option(None, "cut the episode to this many control steps; null: the whole episode")
    width: int = option(640, "video width in pixels (even)")
    height: int = option(480, "video height in pixels (even)")

    def __post_init__(self) -> None:
        super().__post_init__()
        for name in ("width", "height"):
            size = getattr(self, name)
            require(size >= 2 and not size % 2, f"{name} must be even and >= 2 (H.264 needs it), got {size}")
        require(self.episode >= 0, f"episode must be >= 0, got {self.episode}")
        require(self.steps is None or self.steps >= 1, f"steps must be >= 1 or null, got {self.steps}")


@dataclass
class ReportConfig:
    """`colmo-report`: compare the search variants of one sweep, read back from MLflow."""

    # Typed Any: structured configs allow no union of a string and a list. A tuple once validated.
    experiment: Any = option(MISSING, "the MLflow experiment(s) to read, named after their task: pendulum, or a list: [pendulum,cheetah]")
    sweep: str = option("latest", "which runs count: latest (the latest -m sweep), all (every run), or the sweep whose parent run has this name")
    axis: Any = option(
        ["samples", "seconds"], "x of the best-so-far figures: samples, evaluations or seconds, or a list ([samples,seconds]): "
        "a figure against each, the tables read as against the first",
    )
    out: Optional[str] = option(None, "a new directory for report.md and best_so_far.png; null: reports/<experiments>_<date>_<time>")
    tracking_uri: Optional[str] = option(None, "null: sqlite:///mlruns.db in the working directory")

    def __post_init__(self) -> None:
        self.experiment = _names(self.experiment, "experiment")
        require(bool(self.experiment), "experiment=NAME is required")
        self.axis = _names(self.axis, "axis")
        require(bool(self.axis), "axis=NAME is required")  # which names: the report's (colmo.report.__main__.check_inputs)


def _names(value: Any, key: str) -> tuple[str, ...]:
    """One name, a list of names, or names separated by commas (quoted: key='a,b'), as a tuple."""
    entries = [value] if isinstance(value, str) else value
    require(
        isinstance(entries, (list, tuple)) and all(isinstance(entry, str) for entry in entries),
        f"{key} must be one name or a list of names, got {value!r}",
    )
    return tuple(name for entry in entries for name in entry.split(",") if name)
