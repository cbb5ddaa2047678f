"""`colmo task=... llm=... gfo=...` (or `python -m colmo ...`): run a policy search, or a sweep with -m."""

from __future__ import annotations

import dataclasses
import logging
import shlex
import sys
from pathlib import Path
from typing import Optional

from hydra.core.hydra_config import HydraConfig

from colmo.cli import hydra_app
from colmo.config import OpenAIConfig, SearchConfig
from colmo.errors import ConfigError, RunError
from colmo.shell import shell_override
from colmo.trackers import make_tracker


def check_inputs(cfg: SearchConfig) -> None:
    """The spec file loads, `resume=` names a run made with the same scoring settings, and with
    `llm=openai` a server answers, and `finish.retune_budget` has a method that tunes: all before
    any output directory, MLflow run or sandbox exists. (Imports here, not above: shell completion
    imports this module on every Tab.)"""
    from colmo.optimize.methods import tunes_constants
    from colmo.specs import load_task_spec
    from colmo.store import open_for_resume, run_settings

    load_task_spec(cfg.task.spec)
    if cfg.finish.retune_budget and not tunes_constants(cfg.gfo):
        raise ConfigError(
            f"finish.retune_budget={cfg.finish.retune_budget} re-tunes with gfo.method, and gfo={cfg.gfo.method} tunes nothing: "
            "pick a gfo that tunes, or finish.retune_budget=0"
        )
    if cfg.resume:
        open_for_resume(Path(cfg.resume).expanduser(), run_settings(cfg))
    if isinstance(cfg.llm, OpenAIConfig):
        check_servers(cfg)


def check_servers(cfg: SearchConfig) -> None:
    """`RunError` unless one of `llm.base_url`'s servers answers a real request: the generator is
    started (it asks each server for its models), sends one request of a one-token answer, and is
    closed again; the search starts its own."""
    from colmo.generate import GeneratorError, make_generator

    try:
        generator = make_generator(cfg.llm, cfg.seed)
        try:
            generator.check_request()
        finally:
            generator.close()
    except GeneratorError as error:
        raise RunError(f"llm={cfg.llm.name}: {error}") from None


@hydra_app("search", check=check_inputs)
def main(cfg: SearchConfig) -> Optional[float]:
    """Search for a control policy: a generator writes programs, a gradient-free optimizer tunes
    their constants in sandboxed MuJoCo simulation, the best go back into the prompts.

    Returns the best training score (None if the run has no result of its own): the objective a
    Hydra sweeper such as Optuna's maximizes (colmo/conf/hydra/sweeper/optuna.yaml). A run with
    no result ends with a line saying why and exit code 1; in a `-m` sweep the other jobs go on
    and the sweep's end says which failed (`colmo.sweep_comparison`).

    A sweep run again into the same directory (`hydra.sweep.dir=DIR`) keeps each job that has a
    result there and resumes every other one from its store (`resume=`, with the same checks)."""
    from hydra.types import RunMode

    from colmo.timelimit import job_start

    sweep_job = HydraConfig.get().mode == RunMode.MULTIRUN
    started = job_start(sweep_job)  # before the heavy imports, which are the job's start-up
    from colmo.progress import progress
    from colmo.record import summary_failure
    from colmo.search import Search
    from colmo.store import BEST_POLICY_FILE, holds_run, open_for_resume, read_summary, run_settings

    run_dir = Path(HydraConfig.get().runtime.output_dir)
    if sweep_job and not cfg.resume and holds_run(run_dir):  # the sweep runs again into its directory
        earlier = read_summary(run_dir)
        if summary_failure(earlier) is None:
            print(f"this job finished earlier in {run_dir}: best score {earlier['best_score']:.2f}; kept")
            return earlier["best_score"]
        cfg = dataclasses.replace(cfg, resume=str(run_dir))
        open_for_resume(run_dir, run_settings(cfg))  # the same settings, or one line and exit 2
        logging.getLogger("colmo").info("this job resumes its earlier run in %s", run_dir)
    search = Search(cfg, run_dir, make_tracker(cfg.tracker).search_observers(cfg, run_dir), started=started)
    with progress(search):
        summary = search.run()
    print(summary.best_code or "")
    heldout = f", held-out {summary.best_heldout_score:.2f}" if summary.best_heldout_score is not None else ""
    if any(entry["key"] == summary.best_key and entry.get("episodes_alike") for entry in summary.heldout):
        heldout += " (its training episodes all returned the same: held-out episodes repeat them)"
    best = "no program evaluated" if summary.best_score is None else f"best score {summary.best_score:.2f}{heldout}"
    print(
        f"{best} after {summary.samples} samples "
        f"({summary.programs_evaluated} evaluated, {summary.duplicates_skipped} duplicates, "
        f"{summary.failures} failures, {summary.unusable_outputs} unusable) in {summary.seconds:.0f} s "
        f"(load {summary.load:.1f} on {summary.cpus} CPUs); stopped: {summary.stop_reason}"
    )
    print(f"run directory: {summary.run_dir}")
    if summary.resumable and sweep_job:
        hydra = HydraConfig.get()
        sweep_dir = (Path(hydra.runtime.cwd) / hydra.sweep.dir).resolve()
        again = shell_override("hydra.sweep.dir", sweep_dir)
        print(f"resume the sweep with the same command and {again}: finished jobs are kept, the others resumed", file=sys.stderr)
    elif summary.resumable:
        overrides = " ".join(shlex.quote(o) for o in HydraConfig.get().overrides.task if not o.startswith("resume="))
        print(f"resume with: colmo {overrides} {shell_override('resume', summary.run_dir)}".replace("  ", " "), file=sys.stderr)
        if summary.best_code:  # what the finish would have made, for the best so far, without resuming
            policy = f"task={cfg.task.name} seed={cfg.seed} {shell_override('policy_file', Path(summary.run_dir) / BEST_POLICY_FILE)}"
            print(f"or score, simplify and film its best so far: colmo-evaluate {policy}; colmo-simplify {policy}; colmo-render {policy}", file=sys.stderr)
    if summary.failure is None:
        return summary.best_score
    if summary.stop_reason == "interrupted":  # Ctrl-C stops a sweep too
        sys.exit(130)
    if not sweep_job:
        print(f"colmo: error: {summary.failure}", file=sys.stderr)
        sys.exit(1)
    logging.getLogger("colmo").error("this job failed: %s", summary.failure)  # the sweep goes on, and ends saying so
    return None


if __name__ == "__main__":
    main()
