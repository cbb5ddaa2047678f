#!/usr/bin/env bash
# Issue 19's measure of wasted model calls: the share of model calls that yield a program that
# is evaluated, with Qwen2.5-Coder-1.5B-Instruct (Q4_K_M GGUF) in process with `llm=llamacpp`'s
# defaults (prompt form, temperatures, duplicate retries), on the pendulum, GFO (the default),
# one evaluation worker, 48 model calls per run, seeds 0 1 2: one `colmo -m` sweep into OUT,
# resumed where it stopped when run again.
#
#   scripts/llm_model_call_yield.sh                          # OUT=runs/llm-model-call-yield, SEEDS=0,1,2
#   SEEDS=3,4 scripts/llm_model_call_yield.sh llm.prompt_format=completion   # later overrides win
#   (cd runs/llm-model-call-yield && colmo-report experiment=pendulum)      # "Model calls that yield a program"
#
# No time limit (search.max_seconds=0): the count of 48 calls is what is measured. Held-out
# scores are kept; the video and the simplification are left out (not what is measured).
set -euo pipefail
model="${MODEL:-$(python "$(dirname "$0")/fetch_test_model.py" --size 1.5b)}"
out="${OUT:-runs/llm-model-call-yield}"
mkdir -p "$out" && cd "$out"
exec colmo -m "seed=${SEEDS:-0,1,2}" task=pendulum llm=llamacpp "llm.model_path=$model" executor.workers=1 search.max_samples=48 \
  search.max_seconds=0 finish.render=false finish.simplify=false search.progress=false hydra.sweep.dir=sweep "$@"
