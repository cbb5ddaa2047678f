#!/usr/bin/env bash
# How much tuning each program is worth: (1+1)-ES with 25, 50, 100 (the paper) and 200
# evaluations per program, two seeds. The report tells the budgets apart by their gfo.budget
# param; so does the MLflow UI's colmo view (a column).
#
#   multirun_examples/gfo_budget.sh [task=...] [more overrides]
#   colmo-report experiment=pendulum
set -euo pipefail
exec colmo -m task=pendulum gfo=oneplusone gfo.budget=25,50,100,200 seed=0,1 search.max_samples=200 "$@"
