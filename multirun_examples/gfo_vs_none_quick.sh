#!/usr/bin/env bash
# A few-minute version of gfo_vs_none.sh and its report (docs/report/ is one such report).
# 64 programs per run, 3 episodes per score, (1+1)-ES budget 30, seeds 0 and 1, into the
# experiment "pendulum-quick" of ./mlruns.db; then Table I, Fig. 4 and the best policies in a
# new directory reports/pendulum-quick_<date>_<time>/ (or REPORT_DIR, which must not hold a report).
#
#   multirun_examples/gfo_vs_none_quick.sh [more sweep overrides]
set -euo pipefail
colmo -m task=pendulum gfo=none,oneplusone seed=0,1 search.max_samples=64 task.episodes=3 \
    gfo.budget=30 tracker.experiment=pendulum-quick "$@"
if [ -n "${REPORT_DIR:-}" ]; then
    colmo-report experiment=pendulum-quick out="$REPORT_DIR"
else
    colmo-report experiment=pendulum-quick
fi
