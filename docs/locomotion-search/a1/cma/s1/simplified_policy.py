# colmo: the best policy of a1 simplified: training score 140.91, held-out 143.11
# cut short at the finish's deadline after 2 round(s); to go on: colmo-simplify task=a1 seed=1 "policy_file='/work/runs/loco/a1/cma/s1/0_gfo=cma,llm=mutate,search.max_samples=1000000,search.max_seconds=1800,search.progress=False,seed=1,task=a1/best_policy.py'"
import numpy as np

def policy(obs):
    action = -1.402 * (obs[6] + 0.1104 * obs[6] * obs[21])
    return action + np.array([0.3548, 0.3449, -1.114, -0.1307, -0.06981, 0.132, 0.5474, 0.09635, 0.1887, -0.7508, -0.3838, 0.2056]) * np.arctan2(obs[24], obs[23])
