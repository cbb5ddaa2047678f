#!/usr/bin/env bash
# A few-minute version of gfo_vs_none.sh and its report: the run behind docs/report/.
# 64 programs per run, 3 episodes per score, (1+1)-ES budget 30, seeds 0 and 1, into the
# experiment "pendulum-quick" of ./mlruns.db; then Table I, Fig. 4 and the best policies in
# ${REPORT_DIR:-docs/report}.
#
#   multirun_examples/gfo_vs_none_quick.sh [more sweep overrides]
set -euo pipefail
python -m colmo -m task=pendulum gfo=none,oneplusone seed=0,1 search.max_samples=64 task.episodes=3 \
    gfo.budget=30 tracker.experiment=pendulum-quick "$@"
python -m colmo.report experiment=pendulum-quick out="${REPORT_DIR:-docs/report}"
