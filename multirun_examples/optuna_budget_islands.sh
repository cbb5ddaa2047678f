#!/usr/bin/env bash
# An Optuna sweep that searches (pip install "colmo[sweep]"): TPE tunes the GFO budget and the
# number of islands for the best score per CPU-second. Every trial gets the same compute, 10
# minutes on all cores (search.max_seconds, executor.workers=0; search.max_samples high enough
# never to stop it first), so the best training score a trial reaches, which `colmo` returns as
# the objective, is its score per CPU-second budget; a bigger budget tunes each program better
# but samples fewer programs in the same time. 20 trials by default, one after the other.
#
#   multirun_examples/optuna_budget_islands.sh [task=...] [hydra.sweeper.optuna_config.n_trials=40] [more overrides]
#   colmo-report experiment=pendulum axis=seconds     # then compare the trials per second
set -euo pipefail
exec colmo -m hydra/sweeper=optuna 'gfo.budget=tag(int, interval(10, 200))' 'database.num_islands=choice(2, 5, 10)' \
    task=pendulum search.max_seconds=600 search.max_samples=1000000 executor.workers=0 "$@"
