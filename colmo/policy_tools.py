"""What the one-file tools share (`colmo-optimize`, `-evaluate`, `-simplify`, `-render`): the check
of their inputs, the evaluator set up for a policy file, and the result they leave behind.

Each tool works on one policy file for a task (`colmo.config.PolicyFileConfig`):
`check_policy_file` vets the file before Hydra starts (one `ConfigError` line), `policy_session`
makes the executor, the task's evaluator on the training episodes of the run seed (time limits
calibrated on the spec's starter) and the program the file holds, and closes the executor when
the tool is done with them. `write_result` leaves the tool's policy file and `result.json` in
the run directory and says where; `print_result` prints the closing JSON line scripts read.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional

from colmo.config import PolicyFileConfig
from colmo.evaluation import Evaluation, Evaluator, Executor
from colmo.heldout import branch_counts, heldout_evaluator, task_evaluator
from colmo.intake import read_policy_file
from colmo.program import ParametricProgram
from colmo.provenance import provenance
from colmo.specs import Spec, load_task_spec

RESULT_FILE = "result.json"


@dataclass(frozen=True)
class PolicySession:
    """A policy file's program with the executor and the task evaluator that score it."""

    executor: Executor
    spec: Spec
    evaluator: Evaluator  # the training episodes of the run seed
    program: ParametricProgram
    seed: int

    def heldout(self, episodes: int) -> Evaluator:
        """The evaluator on `episodes` held-out episodes of the run seed (the same for every tool)."""
        return heldout_evaluator(self.evaluator, self.seed, episodes)

    def branch_counts(self, evaluator: Evaluator) -> Evaluation:
        """The fast path's evaluation of the policy on `evaluator`'s episodes, spread over the
        workers, with what each of its branches did (`colmo.coverage`)."""
        return branch_counts(self.executor, evaluator, self.program.skeleton, self.program.values)


def check_policy_file(cfg: PolicyFileConfig) -> Spec:
    """The task's spec, once its file loads and the policy file holds a usable policy
    (`ConfigError` otherwise)."""
    spec = load_task_spec(cfg.task.spec)
    read_policy_file(cfg.policy_file, spec.allowed_imports)
    return spec


@contextmanager
def policy_session(cfg: PolicyFileConfig, max_workers: Optional[int] = None) -> Iterator[PolicySession]:
    """The executor `cfg.executor` names (at most `max_workers` workers when given), the task
    evaluator and the policy file's program; the executor is closed on leaving."""
    from colmo.executor import make_executor

    executor = make_executor(cfg.executor, max_workers)
    try:
        spec, evaluator = task_evaluator(cfg.task, cfg.executor, executor, cfg.seed)
        yield PolicySession(executor, spec, evaluator, read_policy_file(cfg.policy_file, spec.allowed_imports), cfg.seed)
    finally:
        executor.close()


def run_directory() -> Path:
    """The Hydra job's output directory."""
    from hydra.core.hydra_config import HydraConfig

    return Path(HydraConfig.get().runtime.output_dir)


def write_result_file(summary: dict[str, Any]) -> Path:
    """Write `result.json` (`summary` and the run's `colmo.provenance`) into the run directory
    and return its path."""
    result = run_directory() / RESULT_FILE
    result.write_text(json.dumps({**summary, "provenance": provenance()}, indent=2))
    return result


def write_result(summary: dict[str, Any], policy_name: str, policy_text: str) -> list[Path]:
    """Write the tool's policy file and `result.json` (`write_result_file`) into the run
    directory, say where on stderr, and return both paths."""
    policy = run_directory() / policy_name
    policy.write_text(policy_text)
    result = write_result_file(summary)
    print(f"wrote {policy} and {result}", file=sys.stderr)
    return [policy, result]


def print_result(summary: dict[str, Any]) -> None:
    """The tool's last stdout line: its result as one JSON object."""
    print(json.dumps(summary))
