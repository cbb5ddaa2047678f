#!/usr/bin/env bash
# How much tuning each program is worth: (1+1)-ES with 25, 50, 100 (the paper) and 200
# evaluations per program, two seeds. The run name carries the budget, which the Hydra choices
# alone do not (they are the same for every job).
#
#   multirun_examples/gfo_budget.sh [task=...] [more overrides]
#   python -m colmo.report experiment=pendulum
set -euo pipefail
exec python -m colmo -m task=pendulum gfo=oneplusone gfo.budget=25,50,100,200 seed=0,1 search.max_samples=200 \
    'tracker.run_name=${task.name}-oneplusone-b${gfo.budget}-s${seed}' "$@"
