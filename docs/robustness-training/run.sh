#!/usr/bin/env bash
# Issue 23 part 3: the same search nominal vs perturbed (task.perturb, every factor at 10%),
# pendulum and cheetah, seeds 0-2, then each winner's robustness curve on nominal held-out
# episodes. Sample-count limits (not seconds), so results do not depend on the machine's load.
# Runs sequentially; each finished run's small outputs go to docs/robustness-training/runs/.
# Usage: docs/robustness-training/run.sh OUTDIR   (runs from the checkout it sits in)
set -u
out=${1:?usage: run.sh OUTDIR}
repo=$(cd "$(dirname "$0")/../.." && pwd)
dest=$repo/docs/robustness-training/runs
mkdir -p "$out" "$dest"
samples_pendulum=25
samples_cheetah=25
perturbed="task.perturb.mass=0.1 task.perturb.damping=0.1 task.perturb.frictionloss=0.1 task.perturb.friction=0.1 task.perturb.gain=0.1 task.perturb.obs_noise=0.1 task.perturb.action_noise=0.1"
for seed in 0 1 2; do
  for task in pendulum cheetah; do
    for variant in nominal perturbed; do
      name=${task}_${variant}_s${seed}
      [ -f "$dest/$name/robustness.json" ] && continue
      samples_var=samples_$task
      extra=""; [ "$variant" = perturbed ] && extra=$perturbed
      echo "$(date +%T) search $name"
      # shellcheck disable=SC2086
      nice -n 10 python -m colmo task=$task llm=mutate gfo=none executor.workers=1 seed=$seed \
        search.max_samples=${!samples_var} search.max_seconds=0 search.progress=false \
        heldout.episodes=10 finish.top=1 finish.render=false finish.simplify=false \
        tracker=none hydra.run.dir="$out/$name" $extra > "$out/$name.search.log" 2>&1 || { echo "search $name failed"; continue; }
      echo "$(date +%T) robustness $name"
      nice -n 10 python -m colmo.evaluate task=$task policy_file="$out/$name/best_policy.py" executor.workers=1 seed=0 \
        episodes=20 robustness=true robustness_episodes=3 'robustness_magnitudes=[0.1,0.2]' 'robustness_delays=[1]' \
        hydra.run.dir="$out/$name/robustness" > "$out/$name.robustness.out" 2> "$out/$name.robustness.log" || { echo "robustness $name failed"; continue; }
      mkdir -p "$dest/$name"
      cp "$out/$name/best_policy.py" "$out/$name/summary.json" "$out/$name/robustness/robustness.csv" "$dest/$name/"
      tail -1 "$out/$name.robustness.out" > "$dest/$name/robustness.json"
      (cd "$repo" && git add "$dest/$name" && for i in 1 2 3 4 5; do git commit -q -m "docs/robustness-training: $name (issue 23 part 3 run)" -- "$dest/$name" && break; sleep 2; done)
      echo "$(date +%T) done $name"
    done
  done
done
echo "$(date +%T) all done"
