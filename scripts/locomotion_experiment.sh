#!/usr/bin/env bash
# Issue 34 part 3, exploration: why locomotion searches stall, one seed and 30 minutes a run
# (search.max_seconds=1800, everything included), colmo's embedded mutation (llm=mutate), two
# evaluation workers. Each variant changes one thing against the default:
#   cheetah/default     with mutation's actuator terms (a gain per joint); mixed-generation's
#                       cheetah mutate runs are the same search before them
#   quadruped/default   the corrected task (upright start), GFO (1+1)-ES
#   cheetah/cma         GFO CMA-ES instead of (1+1)-ES
#   cheetah/episodes20  20 training episodes instead of 10 (its winners lost 20-90 held-out)
#   quadruped/cma       GFO CMA-ES
#   quadruped/noise     starts whose hinges are up to 0.05 rad off (episodes that differ, so held-out scores say something)
#   quadruped/cma_noise GFO CMA-ES on those starts (it tuned the paper's 44 constants to 265 held out, (1+1)-ES to 211)
#   quadruped/finish_retune  quadruped/noise with the finish's re-tuning of the simplified winner at 1000 evaluations
#                       (finish.retune_budget=1000), inside the same time limit
#   a1/default          the Unitree A1 (MENAGERIE_ROOT: a Menagerie tree with unitree_a1)
#   a1/cma              GFO CMA-ES on the A1
#   a1/seconds3         3-second episodes (3000 steps): one second pays a topple, three pay a gait
#   a1/episodes20       20 training episodes instead of 10 (its winners lost 5-20 held-out)
# Each run is a one-job sweep into its own directory, so running this again keeps what finished
# and resumes the rest (a resumed run's time limit is the whole run's). RUN_SECONDS sets another
# length (the goal is within an hour: RUN_SECONDS=3600 into another OUT).
#
#   [RUN_SECONDS=3600] scripts/locomotion_experiment.sh OUT [SEED [TASK/VARIANT ...]]   all twelve variants unless named
#   python scripts/mixed_summary.py OUT        the table (its comparison is with a `mutate` variant, if any)
set -u
out=$(mkdir -p "$1" && cd "$1" && pwd)
seed=${2:-0}
seconds=${RUN_SECONDS:-1800}
shift $(($# < 2 ? $# : 2))
wanted=" $* "
cd "$out"
run() {  # task variant overrides...
  local task=$1 variant=$2; shift 2
  [ "$wanted" = "  " ] || [[ "$wanted" == *" $task/$variant "* ]] || return 0
  colmo -m "task=$task" "seed=$seed" llm=mutate "search.max_seconds=$seconds" search.max_samples=1000000 search.progress=false \
    "hydra.sweep.dir=$task/$variant/s$seed" "$@" || echo "run $task $variant s$seed exited $?"
}
run cheetah default
run quadruped default
run cheetah cma gfo=cma
run cheetah episodes20 task.episodes=20
run quadruped cma gfo=cma
run quadruped noise +task.env.joint_noise=0.05
run quadruped cma_noise gfo=cma +task.env.joint_noise=0.05
run quadruped finish_retune +task.env.joint_noise=0.05 finish.retune_budget=1000
run a1 default
run a1 cma gfo=cma
run a1 seconds3 +task.env.horizon=3000
run a1 episodes20 task.episodes=20
