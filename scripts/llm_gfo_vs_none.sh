#!/usr/bin/env bash
# The paper's main comparison with a real language model: Qwen2.5-Coder-1.5B-Instruct (Q4_K_M
# GGUF) writes every program, in-process with llama.cpp on one thread, on the pendulum; the
# search without GFO against in-the-loop (1+1)-ES tuning (budget 100, 10 episodes per score),
# the same 48 LLM samples per run, seeds 0 and 1, one MLflow experiment.
#
#   scripts/llm_gfo_vs_none.sh                                    # pendulum, 4 runs
#   scripts/llm_gfo_vs_none.sh task=cheetah tracker.experiment=cheetah-llm   # later overrides win
#   python -m colmo.report experiment=pendulum-llm out=docs/llm-pendulum     # then the report
#
# Completion form: measured on these prompts, the 1.5B model's continuations were valid more
# often than its chat answers (24/24 against 20/24) and cost half the tokens. One core is left
# to the model (llm.n_threads=1) and one to the evaluation worker (executor.workers=1): on a
# 2-core machine, 1 model thread generated faster than 2 while the evaluator ran.
# Expected time on 2 cores: 48 samples at 6-20 s each, 5-16 min of generation per run, which
# the evaluation overlaps; a GFO run may take longer where evaluation is the bottleneck.
set -euo pipefail
model="$(python "$(dirname "$0")/fetch_test_model.py" --size 1.5b)"
exec python -m colmo -m task=pendulum llm=llamacpp "llm.model_path=$model" llm.prompt_format=completion \
  llm.n_threads=1 executor.workers=1 gfo=none,oneplusone seed=0,1 search.max_samples=48 \
  tracker=mlflow tracker.experiment=pendulum-llm "$@"
