#!/usr/bin/env bash
# Does showing programs as they ran change a search? (issue 38 part 2.) Qwen2.5-Coder-1.5B-Instruct
# (Q4_K_M GGUF, in process, one model thread) writes every program on the pendulum, GFO defaults,
# one evaluation worker, 80 model calls a run (equal calls, no time limit), prompts showing each
# program without its never-taken branches (database.shown_as_run=true, the default) against as
# stored (false), seeds 0 1 2 paired: one `colmo -m` sweep into OUT, resumable by running it again.
#
#   scripts/shown_as_run_experiment.sh            # OUT=runs/shown-as-run
#   (cd runs/shown-as-run/sweep && colmo-report)  # best, held-out and model-call yield per variant
#
# Expected time on 2 cores: 10-20 minutes a run, 6 runs.
set -euo pipefail
model="${MODEL:-$(python "$(dirname "$0")/fetch_test_model.py" --size 1.5b)}"
out="${OUT:-runs/shown-as-run}"
mkdir -p "$out" && cd "$out"
exec colmo -m "seed=${SEEDS:-0,1,2}" database.shown_as_run=true,false task=pendulum llm=llamacpp "llm.model_path=$model" \
  executor.workers=1 search.max_samples=80 search.max_seconds=0 finish.render=false search.progress=false \
  hydra.sweep.dir=sweep "$@"
