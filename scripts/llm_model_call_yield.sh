#!/usr/bin/env bash
# Issue 19's measure of wasted model calls: the share of model calls that yield a program that
# is evaluated, with Qwen2.5-Coder-1.5B-Instruct (Q4_K_M GGUF) in process with `llm=llamacpp`'s
# defaults (prompt form, temperatures, duplicate retries), on the pendulum, GFO (the default),
# one evaluation worker, 48 model calls per run, seeds 0 1 2, one run after another. Each run
# has its own fixed directory under OUT; a finished one is skipped, a stopped one resumed.
#
#   scripts/llm_model_call_yield.sh                        # OUT=runs/llm-model-call-yield, SEEDS="0 1 2"
#   SEEDS="3 4" scripts/llm_model_call_yield.sh llm.prompt_format=completion   # later overrides win
#   python scripts/llm_runs_table.py runs/llm-model-call-yield/s*               # the table
#
# No time limit (search.max_seconds=0): the count of 48 calls is what is measured. Held-out
# scores are kept; the video and the simplification are left out (not what is measured).
set -euo pipefail
model="${MODEL:-$(python "$(dirname "$0")/fetch_test_model.py" --size 1.5b)}"
out="${OUT:-runs/llm-model-call-yield}"
for seed in ${SEEDS:-0 1 2}; do
  dir="$out/s$seed"
  if python -c 'import json, sys; sys.exit(json.load(open(sys.argv[1]))["stop_reason"] not in ("max_samples", "stop_at_score"))' \
      "$dir/summary.json" 2>/dev/null; then
    echo "seed $seed: finished in $dir, skipped"
    continue
  fi
  resume=()
  if [ -f "$dir/programs.db" ]; then resume=("resume=$dir"); fi
  python -m colmo task=pendulum llm=llamacpp "llm.model_path=$model" executor.workers=1 \
    search.max_samples=48 search.max_seconds=0 "seed=$seed" tracker=none evaluation.render=false \
    evaluation.simplify=false search.progress=false "hydra.run.dir=$dir" "${resume[@]}" "$@"
done
