"""The programs database (paper Sec. IV-D, after FunSearch): which programs are kept, how they
are grouped into islands and clusters, and which ones a prompt shows.

- Islands evolve independently: a prompt shows programs of one island, and what is generated
  from it is registered back into that island. Every island starts with the starter program.
- Within an island, programs with the same score form a cluster. FunSearch clusters by the
  signature of per-test scores; a colmo score is one mean return, so the signature is the
  score itself.
- A prompt is drawn in two stages: a uniformly random island, then clusters by a softmax over
  their scores whose temperature is annealed (FunSearch's schedule), then within each cluster
  a program, shorter ones preferred. Size counts in AST nodes (`colmo.astutil.node_count`).
  With `size_penalty`, a cluster is drawn by its score less `size_penalty` points per AST node
  of its smallest program, so a slightly better but much bigger program does not crowd the
  readable ones out of the prompts (programs above `max_nodes` are refused before they are
  evaluated, by the search). Programs above `max_shown_nodes` are kept and can be the best, but
  a prompt never shows them: it must fit the model's context.
- Every `reset_every` samples the weaker half of the islands is emptied and each is re-seeded
  with the best program of a randomly chosen surviving island.
- Programs are identified by a key (`identity`), and a key already evaluated, successfully
  or not, is never evaluated again. With GFO the key is the structure key (the code with its
  constants abstracted): the optimizer already searched that structure's constants, so two
  programs that differ only in their constants never both reach a prompt. With `gfo=none`
  the key is the program itself (its structure and its constants): constants are all that
  search can change without GFO, so a program with new constants is a new program, as in
  FunSearch and the paper's baseline.

All randomness comes from `seed`. Selection and resets draw from two separate generators, so
the island contents after replaying the same `register`/`mark_seen`/`on_sample` calls are the
same however many prompts were drawn in between: a resumed run rebuilds its state from the
program store without re-drawing its prompts.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from colmo.config import DatabaseConfig
from colmo.program import ParametricProgram, measure


def identity(program: ParametricProgram, by_structure: bool) -> ParametricProgram:
    """`program` keyed as the database tells programs apart: by its structure key (with GFO),
    or by its structure and constants (`gfo=none`)."""
    if by_structure:
        return program
    constants = hashlib.sha256(f"{program.key}{program.values!r}".encode()).hexdigest()
    return dataclasses.replace(program, key=constants)


@dataclass(frozen=True)
class StoredProgram:
    key: str  # the program's `identity` key: with GFO, programs differing only in their constants share it
    code: str  # readable code with the tuned constants inlined (what prompts show)
    score: float  # finite: failed programs are never registered
    island: int
    sample: int  # sample index at which it was generated
    nodes: Optional[int] = None  # AST nodes: its size to read; measured from `code` if not given
    coverage: Optional[tuple[tuple[int, int, int], ...]] = None  # what each branch did when it was scored (`colmo.coverage`)

    def __post_init__(self) -> None:
        if self.nodes is None:
            object.__setattr__(self, "nodes", measure(self.code).nodes)


@dataclass(frozen=True)
class Selection:
    island: int
    programs: list[StoredProgram]  # at most functions_per_prompt, ascending score


@dataclass
class _Island:
    clusters: dict[float, list[StoredProgram]] = field(default_factory=dict)  # by score
    lengths: dict[str, int] = field(default_factory=dict)  # AST nodes of each program, by key
    best: StoredProgram | None = None

    @property
    def size(self) -> int:
        return len(self.lengths)


def _softmax(logits: np.ndarray) -> np.ndarray:
    # Shifting by the max keeps exp() finite at the near-zero temperatures of the schedule.
    weights = np.exp(logits - logits.max())
    return weights / weights.sum()


class ProgramDatabase:
    def __init__(self, cfg: DatabaseConfig, starter: StoredProgram, seed: int) -> None:
        """`starter` is registered in every island (its own `island` field is ignored)."""
        self.cfg = cfg
        self._select_rng = np.random.default_rng([seed, 0])
        self._reset_rng = np.random.default_rng([seed, 1])
        self._islands = [_Island() for _ in range(cfg.num_islands)]
        self._seen: set[str] = set()
        self._best: StoredProgram | None = None
        self._reset_period = 0
        for island in range(cfg.num_islands):
            self.register(dataclasses.replace(starter, island=island))

    # -- prompts --------------------------------------------------------------------------

    def select(self) -> Selection:
        """Programs of one island for the next prompt, ascending score: of those small enough to
        show (`database.max_shown_nodes`: a hostile or bloated program that scores best would
        otherwise fill every prompt past the model's context, and end the search); an island
        with none shows its smallest program."""
        island_id = int(self._select_rng.integers(len(self._islands)))
        island = self._islands[island_id]
        cap = self.cfg.max_shown_nodes
        shown = {score: [p for p in cluster if cap is None or p.nodes <= cap] for score, cluster in island.clusters.items()}
        shown = {score: cluster for score, cluster in shown.items() if cluster}
        if not shown:
            smallest = min((p for cluster in island.clusters.values() for p in cluster), key=lambda p: p.nodes)
            return Selection(island_id, [smallest])
        scores = np.array([score - self.cfg.size_penalty * min(p.nodes for p in cluster) for score, cluster in shown.items()], dtype=float)
        temperature = self.cluster_temperature(island_id)
        # Clusters are drawn without replacement (FunSearch draws with replacement), so a prompt
        # never shows the same structure twice.
        remaining = list(range(len(scores)))
        chosen = []
        for _ in range(min(len(scores), self.cfg.functions_per_prompt)):
            probabilities = _softmax(scores[remaining] / temperature)
            chosen.append(remaining.pop(self._select_rng.choice(len(remaining), p=probabilities)))
        clusters = list(shown.values())
        programs = [self._pick_in_cluster(island, clusters[i]) for i in chosen]
        return Selection(island_id, sorted(programs, key=lambda program: program.score))

    def cluster_temperature(self, island: int) -> float:
        """FunSearch's schedule: from cluster_temperature_init down towards 0 as the island
        fills up, back to the start every cluster_temperature_period programs."""
        period = self.cfg.cluster_temperature_period
        return self.cfg.cluster_temperature_init * (1 - (self._islands[island].size % period) / period)

    def _pick_in_cluster(self, island: _Island, cluster: list[StoredProgram]) -> StoredProgram:
        """Equal scores: prefer the shorter program, as the simpler explanation of that score."""
        lengths = np.array([island.lengths[program.key] for program in cluster], dtype=float)
        normalized = (lengths - lengths.min()) / (lengths.max() + 1e-6)
        probabilities = _softmax(-normalized / self.cfg.length_temperature)
        return cluster[self._select_rng.choice(len(cluster), p=probabilities)]

    # -- registration ---------------------------------------------------------------------

    def register(self, program: StoredProgram) -> None:
        """Store an evaluated program in `program.island`; its key becomes known."""
        assert math.isfinite(program.score), f"failed program {program.key} cannot be registered"
        island = self._islands[program.island]
        assert program.key not in island.lengths, f"structure {program.key} is already on island {program.island}"
        island.clusters.setdefault(program.score, []).append(program)
        island.lengths[program.key] = program.nodes
        if island.best is None or program.score > island.best.score:
            island.best = program
        if self._best is None or program.score > self._best.score:
            self._best = program
        self._seen.add(program.key)

    def is_known(self, key: str) -> bool:
        """Whether this structure was evaluated (or marked seen) before, in any island."""
        return key in self._seen

    def mark_seen(self, key: str) -> None:
        """A failed or duplicate structure: it is never evaluated again."""
        self._seen.add(key)

    # -- resets ---------------------------------------------------------------------------

    def on_sample(self, samples: int) -> list[int]:
        """Call after each integrated batch with the total samples so far. Resets the weaker
        half of the islands once each time `samples` crosses a multiple of `reset_every`
        (once even if a batch crosses several); returns the reset islands."""
        if not self.cfg.reset_every or samples // self.cfg.reset_every <= self._reset_period:
            return []
        self._reset_period = samples // self.cfg.reset_every
        return self._reset_weaker_half()

    def _reset_weaker_half(self) -> list[int]:
        best = np.array(self.best_per_island)
        # lexsort sorts by the last key first: by best score, ties in a random order.
        order = np.lexsort((self._reset_rng.random(len(best)), best))
        weaker, survivors = sorted(order[: len(best) // 2].tolist()), order[len(best) // 2 :]
        for island in weaker:
            founder = self._islands[self._reset_rng.choice(survivors)].best
            self._islands[island] = _Island()
            self.register(dataclasses.replace(founder, island=island))
        return weaker

    # -- inspection -----------------------------------------------------------------------

    @property
    def best(self) -> StoredProgram:
        """The best program registered so far (the first one to reach the top score)."""
        return self._best

    @property
    def best_per_island(self) -> list[float]:
        return [island.best.score for island in self._islands]

    @property
    def island_sizes(self) -> list[int]:
        return [island.size for island in self._islands]

    @property
    def n_programs(self) -> int:
        return sum(self.island_sizes)

    def programs(self, island: int) -> list[StoredProgram]:
        """The programs held by `island`, cluster by cluster in order of creation."""
        return [program for cluster in self._islands[island].clusters.values() for program in cluster]
