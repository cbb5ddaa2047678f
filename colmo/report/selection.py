"""Which runs a report counts, read back from MLflow: the FINISHED search runs of one sweep of
the experiments (`select_sweep`: the latest, one named, or every run with `sweep=all`; sweep
parents and `colmo-optimize` runs are not searches), with its best-so-far
history against the chosen axis; runs that did not finish are left out with the reason. Runs
are grouped by task and variant: the GFO method, its budget when tuning, and any other setting
that differs between the task's runs (`database.num_islands=5`); settings that do not change
results (tracker, executor, display) are ignored. A run repeated with the same variant and seed
is a repeat: the latest counts, and the report names the older ones."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional, Sequence

from mlflow import MlflowClient
from mlflow.entities import Run
from mlflow.utils.mlflow_tags import MLFLOW_PARENT_RUN_ID

from colmo.optimize.methods import METHODS
from colmo.track import SWEEP_TAG

ALL_RUNS = "all"
LATEST = "latest"
NO_GFO = "no GFO"
# x axes: the metric logged at each step (samples is the step itself) and its label.
AXES = {
    "samples": (None, "model calls (programs sampled)"),
    "evaluations": ("evaluations", "candidate evaluations (each over task.episodes episodes)"),
    "seconds": ("seconds", "seconds of search (wall clock)"),
}
# Settings that do not change what a search finds: not part of a variant (`evaluation.render`:
# `finish.render` in runs logged before its rename).
_IGNORED = ("tracker.", "executor.", "search.progress", "search.queue_size", "finish.render", "evaluation.render", "resume", "spec.")
_VARIANT_BASE = ("task.name", "gfo.method", "gfo.budget", "seed")


@dataclass
class RunCurves:
    """One finished search as the report needs it: its best-so-far curve against `x`."""

    run: Run
    task: str
    method: str
    budget: int
    seed: int
    target: Optional[float]
    variant: str = ""
    steps: list[int] = field(default_factory=list)  # samples so far at each batch
    x: list[float] = field(default_factory=list)  # the chosen axis at each batch
    best: list[float] = field(default_factory=list)
    per_island: list[list[float]] = field(default_factory=list)

    @property
    def tunes_constants(self) -> bool:
        """Whether the run's GFO method changes constants (`gfo=none` does not)."""
        return METHODS[self.method].tunes_constants

    @property
    def order(self) -> tuple:
        """The GFO methods in registry order (no GFO first), by budget when tuning; then seeds."""
        return (self.task, list(METHODS).index(self.method), self.budget if self.tunes_constants else 0, self.variant, self.seed)

    @property
    def final(self) -> float:
        return self.best[-1]

    @property
    def heldout(self) -> Optional[float]:
        return self.run.data.metrics.get("best_heldout_score")

    @property
    def samples_to_target(self) -> Optional[int]:
        """Programs sampled when the best score first reached the target (batch resolution)."""
        if self.target is None:
            return None
        return next((step for step, score in zip(self.steps, self.best) if score >= self.target), None)


@dataclass
class Variant:
    name: str
    runs: list[RunCurves] = field(default_factory=list)

    @property
    def gfo(self) -> bool:
        return self.runs[0].tunes_constants


@dataclass
class Reading:
    """What was read from MLflow: the runs that count, and those left out with the reason."""

    curves: list[RunCurves]
    left_out: list[tuple[Run, str]]
    sweep: str = ""  # which runs were read: the sweep's parent run name(s), or every run


def _all_runs(client: MlflowClient, experiment_ids: list[str]) -> list[Run]:
    """Every run of the experiments, newest first."""
    runs, token = [], None
    while True:
        page = client.search_runs(experiment_ids, "", max_results=1000, order_by=["attributes.start_time DESC"], page_token=token)
        runs += list(page)
        token = page.token
        if not token:
            return runs


def select_sweep(client: MlflowClient, experiment_ids: list[str], sweep: str = LATEST) -> tuple[Optional[set[str]], str]:
    """The parent run ids of the sweep a report reads, and how to name it. `latest`: the latest
    sweep parent with a child job (every run when the experiments hold none: searches started
    without `-m`); `all`: every run (None); else a sweep parent's run name or `colmo.sweep` id.
    A sweep over several tasks has one parent per experiment, all with the same `colmo.sweep`
    id: all of them are the sweep. `ValueError` if no sweep has that name."""
    if sweep == ALL_RUNS:
        return None, "every run of the experiment(s)"
    parents = [run for run in _all_runs(client, experiment_ids) if SWEEP_TAG in run.data.tags]
    if sweep == LATEST:
        def has_child(parent: Run) -> bool:
            query = f"tags.`{MLFLOW_PARENT_RUN_ID}` = '{parent.info.run_id}'"
            return bool(client.search_runs(experiment_ids, query, max_results=1))

        chosen = next((parent for parent in parents if has_child(parent)), None)
        if chosen is None:
            return None, "every run of the experiment(s) (no sweep in them)"
    else:
        chosen = next((p for p in parents if sweep in (p.info.run_name, p.data.tags[SWEEP_TAG])), None)
        if chosen is None:
            names = ", ".join(p.info.run_name for p in parents[:10]) or "none"
            raise ValueError(f"no sweep named {sweep!r} (sweeps, latest first: {names}; or sweep=all)")
    members = [p for p in parents if p.data.tags[SWEEP_TAG] == chosen.data.tags[SWEEP_TAG]]
    return {p.info.run_id for p in members}, "sweep " + ", ".join(sorted(p.info.run_name for p in members))



def _search_runs(client: MlflowClient, experiment_ids: list[str], parents: Optional[set[str]]) -> list[Run]:
    """Every search run (not sweep parents, not colmo-optimize runs) of the sweep with these
    parent runs (every one if None), newest first."""
    return [
        run for run in _all_runs(client, experiment_ids)
        if SWEEP_TAG not in run.data.tags and run.data.tags.get("colmo.command", "search") == "search"
        and (parents is None or run.data.tags.get(MLFLOW_PARENT_RUN_ID) in parents)
    ]


def _history(client: MlflowClient, run_id: str, key: str) -> dict[int, float]:
    """The metric's value at each step (the last one logged there)."""
    return {m.step: m.value for m in sorted(client.get_metric_history(run_id, key), key=lambda m: (m.step, m.timestamp))}


def _setting_key(params: dict[str, str]) -> dict[str, str]:
    return {key: value for key, value in params.items() if not key.startswith(_IGNORED)}


def read_runs(client: MlflowClient, experiments: Sequence[str], axis: str = "samples", sweep: str = LATEST) -> Reading:
    """The finished search runs of one sweep of `experiments` (`select_sweep`) with their
    best-so-far histories against `axis`; the latest of each repeat (same settings and seed) counts, the others are left out
    with the reason, and so are runs that did not finish, evaluated no program or have no curve."""
    ids = []
    for name in experiments:
        experiment = client.get_experiment_by_name(name)
        if experiment is None:
            raise ValueError(f"no MLflow experiment named {name!r} at {client.tracking_uri}")
        ids.append(experiment.experiment_id)
    parents, selected = select_sweep(client, ids, sweep)
    metric, _ = AXES[axis]
    curves: list[RunCurves] = []
    left_out: list[tuple[Run, str]] = []
    counted: dict[tuple, str] = {}  # settings -> run name of the latest run with them
    for run in _search_runs(client, ids, parents):
        params, run_id = run.data.params, run.info.run_id
        if run.info.status != "FINISHED":
            left_out.append((run, f"status {run.info.status}"))
            continue
        if run.data.metrics.get("programs_evaluated") == 0:
            left_out.append((run, "no program of its own evaluated: no result (its best is the starter's)"))
            continue
        settings = tuple(sorted(_setting_key(params).items()))
        if settings in counted:
            left_out.append((run, f"repeat of `{counted[settings]}` (same settings and seed; the latest counts)"))
            continue
        best = _history(client, run_id, "best_score")
        if not best:
            left_out.append((run, "no batch finished: no curve"))
            continue
        xs = {step: float(step) for step in best} if metric is None else _history(client, run_id, metric)
        if not set(best) <= set(xs):
            left_out.append((run, f"no `{metric}` metric at every batch (logged by newer colmo): not on this axis"))
            continue
        counted[settings] = run.info.run_name
        target = params.get("task.target_score", "null")
        curve = RunCurves(
            run=run, task=params["task.name"], method=params["gfo.method"], budget=int(params["gfo.budget"]),
            seed=int(params["seed"]), target=None if target == "null" else float(target),
        )
        curve.steps = sorted(best)
        curve.x = [xs[step] for step in curve.steps]
        curve.best = [best[step] for step in curve.steps]
        islands = sorted((k for k in run.data.metrics if k.startswith("best_score_island_")), key=lambda k: int(k.rsplit("_", 1)[1]))
        for key in islands:
            history = _history(client, run_id, key)
            curve.per_island.append([history.get(step, float("nan")) for step in curve.steps])
        curves.append(curve)
    _name_variants(curves)
    return Reading(curves, left_out, selected)


def _name_variants(curves: list[RunCurves]) -> None:
    """Each run's variant: the GFO method (and budget when tuning), and every other setting
    that differs between the runs of its task."""
    by_task: dict[str, list[RunCurves]] = {}
    for curve in curves:
        by_task.setdefault(curve.task, []).append(curve)
    for runs in by_task.values():
        settings = [_setting_key(curve.run.data.params) for curve in runs]
        # Keys only some runs have belong to one option's schema (gfo.sampler of gfo=bo): the
        # option itself (gfo.method, llm.name) already tells those runs apart.
        shared = set.intersection(*(set(s) for s in settings)) - set(_VARIANT_BASE)
        differing = sorted(key for key in shared if len({s[key] for s in settings}) > 1)
        for curve, setting in zip(runs, settings):
            base = f"{curve.method}, budget {curve.budget}" if curve.tunes_constants else NO_GFO
            extra = [f"{key}={setting[key]}" for key in differing if curve.tunes_constants or not key.startswith("gfo.")]
            curve.variant = ", ".join([base, *extra])


def group(curves: list[RunCurves]) -> dict[str, list[Variant]]:
    """Runs by task, then by variant."""
    tasks: dict[str, dict[str, Variant]] = {}
    for curve in sorted(curves, key=lambda c: c.order):
        tasks.setdefault(curve.task, {}).setdefault(curve.variant, Variant(curve.variant)).runs.append(curve)
    return {task: list(variants.values()) for task, variants in tasks.items()}
