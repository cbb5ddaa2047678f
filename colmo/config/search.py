"""The schemas of the search's own config groups: the programs database, the search loop's
limits, the held-out scores (`heldout`), what the search does at its end (`finish`) and the
simplifier (`simplify`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

from colmo.config.fields import above, at_least, option, require
from colmo.config.task import MAX_EPISODES_HELP, PRECISION_HELP, ROBUSTNESS_DELAYS, ROBUSTNESS_MAGNITUDES, check_robustness_grid

MODEL_SHARES = ("always", "by_yield")  # `search.model_share`: colmo.model_share


@dataclass
class DatabaseConfig:
    """The programs database: islands, clusters, resets (FunSearch's)."""

    num_islands: int = option(10, "islands evolving independently")
    functions_per_prompt: int = option(2, "programs shown in each prompt")
    reset_every: int = option(400, "samples between resets of the weaker half of the islands (0: never)")
    cluster_temperature_init: float = option(0.1, "softmax temperature over cluster scores, annealed to 0 ...")
    cluster_temperature_period: int = option(30000, "... over this many programs per island, then restarted")
    length_temperature: float = option(1.0, "within a cluster, shorter programs are preferred")
    size_penalty: float = option(0.0, "clusters are drawn by score minus this many points per AST node of their smallest program")
    max_nodes: Optional[int] = option(None, "programs bigger than this many AST nodes are refused before they are evaluated; null: no cap")
    max_constants: Optional[int] = option(
        None, "programs with more tunable constants than this are refused before they are evaluated (the starter excepted); null: no cap",
    )
    shown_as_run: bool = option(
        True, "prompts show each program without the branches its final scoring never took (the referee's child counts "
        "them: colmo.coverage); false: as stored",
    )
    max_shown_nodes: Optional[int] = option(
        1000, "programs bigger than this many AST nodes are never shown in a prompt, though they count and can be the best "
        "(the prompt must fit the model's context: a policy of a few hundred nodes is typical); null: no cap",
    )

    def __post_init__(self) -> None:
        at_least(self, "database", num_islands=1, functions_per_prompt=1, cluster_temperature_period=1, size_penalty=0)
        require(self.reset_every >= 0, f"database.reset_every must be >= 0 (0 = never), got {self.reset_every}")
        above(self, "database", cluster_temperature_init=0, length_temperature=0)
        require(self.max_nodes is None or self.max_nodes >= 1, f"database.max_nodes must be >= 1, got {self.max_nodes}")
        require(self.max_constants is None or self.max_constants >= 0, f"database.max_constants must be >= 0, got {self.max_constants}")
        require(self.max_shown_nodes is None or self.max_shown_nodes >= 1, f"database.max_shown_nodes must be >= 1, got {self.max_shown_nodes}")



@dataclass
class HeldoutConfig:
    """Held-out scores: fresh episodes, their seeds disjoint from the training ones."""

    episodes: int = option(100, "held-out episodes per score")

    def __post_init__(self) -> None:
        at_least(self, "heldout", episodes=1)


@dataclass
class FinishConfig:
    """The end of a search (`colmo.finish`): which programs get a held-out score, and what is
    made of the best one."""

    top: int = option(3, "the best programs of a search that get a held-out score (over heldout.episodes) at its end")
    render: bool = option(True, "a video and a plot of the best policy on a held-out episode")
    simplify: bool = option(True, "the best policy simplified (simplified_policy.py; options: simplify.*)")
    simplify_share: float = option(
        0.03, "share of search.max_seconds kept for the simplification at least (at most simplify.max_seconds); 0: the least it needs",
    )
    retune_budget: int = option(
        0, "GFO evaluations (gfo.method and its options) that re-tune the constants of the final policy, the simplified one where "
        "simplification made it, at the end of the search (retuned_policy.py, with its held-out score); 0: none",
    )
    robustness: bool = option(
        False, "the best policy scored over a grid of model-mismatch magnitudes (robustness.json/.csv/.png; colmo.robustness)",
    )
    coverage: bool = option(
        True, "what each branch of the best policy did over the training and held-out episodes (comments in best_policy.py; colmo.coverage)",
    )
    robustness_episodes: int = option(3, "held-out episodes per robustness grid point")
    robustness_precision: Optional[float] = option(None, PRECISION_HELP + " (more only where the finish's time allows)")
    robustness_max_episodes: int = option(320, MAX_EPISODES_HELP)
    robustness_magnitudes: list[float] = option(ROBUSTNESS_MAGNITUDES, "relative magnitudes of the robustness grid (0, nominal, is always scored)")
    robustness_delays: list[int] = option(ROBUSTNESS_DELAYS, "control delays (steps) of the robustness grid")

    def __post_init__(self) -> None:
        at_least(self, "finish", top=1, retune_budget=0)
        require(0 <= self.simplify_share <= 0.2, f"finish.simplify_share must be in [0, 0.2], got {self.simplify_share}")
        check_robustness_grid(
            "finish.", self.robustness_episodes, self.robustness_magnitudes, self.robustness_delays, self.robustness_precision,
            self.robustness_max_episodes,
        )


@dataclass
class SimplifyConfig:
    """The simplifier (`colmo.simplify`): what a deletion may cost, and how far it goes."""

    tolerance: float = option(0.01, "share of the original training score a simplified program may lose (its held-out gap may widen as much)")
    max_rounds: int = option(200, "at most this many deletions")
    batch_size: Optional[int] = option(None, "candidates scored per executor call, largest deletion first; null: 4 per worker")
    max_seconds: Optional[float] = option(
        600.0, "stop after this many seconds with the shortest program so far (a search's finish also stops at its own deadline); null: no limit",
    )
    max_constants: Optional[int] = option(
        None, "a budget of tunable constants: past the tolerance, delete what loses the least score per constant until the program "
        "has at most this many, then re-tune (the loss is reported); null: no budget",
    )

    def __post_init__(self) -> None:
        require(0 <= self.tolerance < 1, f"simplify.tolerance must be in [0, 1), got {self.tolerance}")
        require(self.max_constants is None or self.max_constants >= 0, f"simplify.max_constants must be >= 0 or null, got {self.max_constants}")
        require(self.max_seconds is None or self.max_seconds > 0, f"simplify.max_seconds must be > 0 or null, got {self.max_seconds}")
        at_least(self, "simplify", max_rounds=0)
        require(self.batch_size is None or self.batch_size >= 1, f"simplify.batch_size must be >= 1 or null, got {self.batch_size}")


@dataclass
class SearchLoopConfig:
    """The search loop's limits and display."""

    max_samples: int = option(
        1000, "stop after this many model calls (generator requests' answers), duplicates, their regenerations and failures included",
    )
    duplicate_retries: int = option(
        2, "a sample whose program was already evaluated is generated again, with a fresh seed, up to this many times "
        "(each a model call) before it is recorded as a duplicate: a chat model is told in the same conversation what it "
        "copied (and why an answer of no usable program is refused), other generators are asked from another selection",
    )
    # One hour by default: 1000 quadruped samples at one evaluation a second would take a day and
    # more, and a user should not have to know that to get a run that ends on its own.
    max_seconds: float = option(
        3600.0, "wall-clock limit of the whole run, held-out scores, simplification and video included, from the process's start "
        "(in a -m sweep: from each job's own start); 0: none",
    )
    stop_at_score: Optional[float] = option(None, "stop once the best training score reaches this")
    queue_size: int = option(2, "batches in flight: generation overlaps evaluation")
    steady_state: bool = option(
        False, "instead of llm.batch_size children a prompt and search.queue_size batches in flight, each idle worker gets "
        "one child, from a prompt drawn when it frees, and each program enters the database as soon as it and those before it "
        "are in (asynchronous steady-state evolution, as search.fill draws); for the embedded generator, whose answers take "
        "no time (a model's call would leave the workers idle). The mix of what a prompt shows depends on timing, so such a "
        "run is no longer a deterministic function of its seed",
    )
    steady_queue: int = option(
        0, "with search.steady_state: programs in flight beyond the workers' share, so that a worker that frees finds the "
        "next candidate waiting instead of idling through its program's round trip; each is drawn before the programs "
        "ahead of it are in",
    )
    fill: Optional[str] = option(
        None, "mutate: while the generator's call is in flight, batches of colmo's embedded mutation of the best programs "
        "(the generator's included) keep idle workers busy, in the same islands; samples record which generator made them "
        "(a run is then no longer a deterministic function of its seed: the mix depends on timing)",
    )
    model_share: str = option(
        "by_yield", "with search.fill: by_yield (after each call the model pauses, so that it calls for the share of the "
        "time its island bests per CPU-second earn against the filler's; the filler has the cores meanwhile) or always (the "
        "model is called back to back); without a filler the model is called back to back",
    )
    min_model_share: float = option(0.1, "with search.model_share=by_yield: the least share of the time the model calls for")
    progress: bool = option(True, "live progress display on a terminal, a plain line every progress_every_s otherwise")
    progress_every_s: float = option(30.0, "seconds between plain progress lines when stderr is not a terminal")

    def __post_init__(self) -> None:
        at_least(self, "search", max_samples=1, queue_size=1, duplicate_retries=0, steady_queue=0)
        require(
            self.steady_state or not self.steady_queue,
            "search.steady_queue needs search.steady_state=true (without it, batches queue: search.queue_size)",
        )
        require(self.fill in (None, "mutate"), f"search.fill must be null or mutate, got {self.fill!r}")
        require(self.model_share in MODEL_SHARES, f"search.model_share must be one of {', '.join(MODEL_SHARES)}, got {self.model_share!r}")
        require(0 < self.min_model_share <= 1, f"search.min_model_share must be in (0, 1], got {self.min_model_share}")
        require(self.max_seconds >= 0, f"search.max_seconds must be >= 0 (0 = no limit), got {self.max_seconds}")
        above(self, "search", progress_every_s=0)

