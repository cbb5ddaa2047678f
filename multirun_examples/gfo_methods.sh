#!/usr/bin/env bash
# The GFO methods side by side, same search otherwise: Nevergrad's (1+1)-ES, CMA-ES and
# differential evolution, and Optuna's TPE (Bayesian optimization), budget 100 each, two seeds.
#
#   multirun_examples/gfo_methods.sh [task=...] [more overrides]
#   colmo-report experiment=pendulum
set -euo pipefail
exec colmo -m task=pendulum gfo=oneplusone,cma,de,bo seed=0,1 search.max_samples=200 "$@"
