# colmo: the best policy of cheetah simplified: training score 230.22, held-out 226.86
# cut short at the finish's deadline after 4 round(s); to go on: colmo-simplify task=cheetah seed=0 "policy_file='/work/runs/yield/cheetah/mutate/s0/0_llm=mutate,search.max_samples=1000000,search.max_seconds=1800,search.progress=False,seed=0,task=cheetah/best_policy.py'"
import numpy as np

def policy(obs):
    action = 0.0
    return action - -0.6778 * np.abs(obs[5]) * obs[9] + -0.2655 * obs[1] + np.array([1.733, 0.1936, 2.857, 1.768, -0.08255, -(8.308 * obs[2])]) * np.sign(obs[9]) + 0.0106 * (action + -1.905 * obs[15])
