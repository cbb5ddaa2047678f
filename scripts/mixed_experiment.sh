#!/usr/bin/env bash
# Issue 34 part 2: one search, two generators, at equal wall clock. On each task, 30 minutes a run
# (search.max_seconds=1800, everything included), colmo's defaults otherwise (2 workers):
#   mixed:  the 1.5B model in process (one thread) with search.fill=mutate, called back to back (search.model_share=always)
#   mutate: colmo's embedded mutation alone
#   model:  the 1.5B model alone (seed 0 only)
#   by_yield: mixed, the model's share of the time following its yield (search.model_share=by_yield)
#   steady: mutation alone drawing as the filler draws, a child per idle worker (search.steady_state=true)
#   steady_q: steady with one program queued beyond the workers (search.steady_queue=1)
#   by_yield_c10: by_yield keeping only programs of at most 10 tunable constants (database.max_constants=10)
#   mutate_c10: mutation alone within the same cap
# Seed 0 of every variant first, then seeds 1 and 2. Each run is a one-job sweep into its own
# directory, so running this again keeps what finished and resumes the rest.
#
#   [VARIANTS="by_yield mutate"] [SEEDS="2"] scripts/mixed_experiment.sh OUT [TASK ...]
#                          (default: every variant, seeds 0 1 2; tasks: pendulum cheetah)
#   python scripts/mixed_summary.py OUT               the table of what has finished
set -u
out=$(mkdir -p "$1" && cd "$1" && pwd); shift
tasks=${*:-pendulum cheetah}
variants=" ${VARIANTS:-mixed mutate steady steady_q model by_yield by_yield_c10 mutate_c10} "
model=$(python "$(dirname "$0")/fetch_test_model.py" --size 1.5b)
cd "$out"
run() {  # task variant seed overrides...
  local task=$1 variant=$2 seed=$3; shift 3
  case "$variants" in *" $variant "*) ;; *) return ;; esac
  colmo -m "task=$task" "seed=$seed" search.max_seconds=1800 search.max_samples=1000000 search.progress=false \
    "hydra.sweep.dir=$task/$variant/s$seed" "$@" || echo "run $task $variant s$seed exited $?"
}
for seed in ${SEEDS:-0 1 2}; do
  for task in $tasks; do
    run "$task" mixed "$seed" llm=llamacpp "llm.model_path=$model" search.fill=mutate search.model_share=always
    run "$task" mutate "$seed" llm=mutate
    run "$task" steady "$seed" llm=mutate search.steady_state=true
    run "$task" steady_q "$seed" llm=mutate search.steady_state=true search.steady_queue=1
    if [ "$seed" = 0 ]; then run "$task" model "$seed" llm=llamacpp "llm.model_path=$model"; fi
    run "$task" by_yield "$seed" llm=llamacpp "llm.model_path=$model" search.fill=mutate search.model_share=by_yield
    run "$task" by_yield_c10 "$seed" llm=llamacpp "llm.model_path=$model" search.fill=mutate search.model_share=by_yield database.max_constants=10
    run "$task" mutate_c10 "$seed" llm=mutate database.max_constants=10
  done
done
