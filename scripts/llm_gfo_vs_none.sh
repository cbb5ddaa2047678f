#!/usr/bin/env bash
# The paper's main comparison with a real language model (issue 19 part 3): Qwen2.5-Coder-1.5B-
# Instruct (Q4_K_M GGUF) writes every program, in process with llama.cpp (`llm=llamacpp`'s
# defaults: chat form, one model thread), on the pendulum; the search without GFO against
# in-the-loop (1+1)-ES tuning (budget 100, 10 episodes per score), 200 model calls per run,
# seeds 0 1 2, one evaluation worker: one `colmo -m` sweep into OUT. Run the same command again
# after a stop (Ctrl-C, a restart, a kill): the sweep keeps the finished runs and resumes the others.
#
#   scripts/llm_gfo_vs_none.sh                                   # OUT=runs/llm-gfo-vs-none
#   SEEDS=0,1,2,3,4 scripts/llm_gfo_vs_none.sh task=ball_in_cup  # later overrides win
#   (cd runs/llm-gfo-vs-none && colmo-report experiment=pendulum)  # Table I, both axes, model-call yield
#
# Expected time on 2 quiet cores: a chat answer of the 1.5B model takes 5-15 s, a GFO tuning
# 30-60 s on the one worker (it overlaps generation): 1-3 hours a GFO run, under an hour
# without GFO, 5-10 hours in all. No time limit (search.max_seconds=0): the calls are the budget.
set -euo pipefail
model="${MODEL:-$(python "$(dirname "$0")/fetch_test_model.py" --size 1.5b)}"
out="${OUT:-runs/llm-gfo-vs-none}"
mkdir -p "$out" && cd "$out"
exec colmo -m gfo=none,oneplusone "seed=${SEEDS:-0,1,2}" task=pendulum llm=llamacpp "llm.model_path=$model" executor.workers=1 \
  search.max_samples=200 search.max_seconds=0 finish.render=false search.progress=false hydra.sweep.dir=sweep "$@"
