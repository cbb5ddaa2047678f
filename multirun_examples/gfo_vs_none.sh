#!/usr/bin/env bash
# The paper's main comparison (Table I, Fig. 4): the program search without GFO (each program
# scored with the constants it was written with) and with in-the-loop (1+1)-ES tuning, the
# paper's GFO (budget 100, 10 episodes per score), three seeds each, equal sample budgets.
#
#   multirun_examples/gfo_vs_none.sh                    # pendulum
#   multirun_examples/gfo_vs_none.sh task=cheetah       # any task; later overrides win
#   colmo-report experiment=pendulum          # then: Table I, Fig. 4, best policies
set -euo pipefail
exec colmo -m task=pendulum gfo=none,oneplusone seed=0,1,2 search.max_samples=200 "$@"
