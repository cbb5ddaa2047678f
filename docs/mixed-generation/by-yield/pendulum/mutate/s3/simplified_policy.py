# colmo: the best policy of pendulum simplified: training score 642.10, held-out 737.09
# cut short at the finish's deadline after 4 round(s); to go on: colmo-simplify task=pendulum seed=3 "policy_file='/work/runs/p3/pendulum/mutate/s3/0_llm=mutate,search.max_samples=1000000,search.max_seconds=1800,search.progress=False,seed=3,task=pendulum/best_policy.py'"
import numpy as np

def policy(obs):
    return 407.9 / (70.04 / (-0.3602 * obs[1] - np.abs(-(2.247 - 0.4124 * np.arctan2(obs[2], obs[0])) * obs[2])) * obs[1] - -(3.86 + -0.4163 * (13.9 * obs[0]) - 0.3201 * (np.arctan2(obs[2], obs[0]) - 1.915 * obs[2] * obs[1])) * obs[2]) + 1.898 * obs[0] + 0.9255 * obs[1]
