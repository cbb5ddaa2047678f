# colmo: the best policy of cheetah simplified: training score 251.29, held-out 249.66
# cut short at the finish's deadline after 2 round(s); to go on: colmo-simplify task=cheetah seed=1 "policy_file='/work/runs/yield/cheetah/mutate/s1/0_llm=mutate,search.max_samples=1000000,search.max_seconds=1800,search.progress=False,seed=1,task=cheetah/best_policy.py'"
import numpy as np

def policy(obs):
    return np.array([-0.05216, -0.1128, -0.8684, 0.05027, -0.9584, -0.9899]) * np.sign(obs[2]) + np.array([0.5456, -0.1524, -0.2046, 0.534, -0.3121, -(0.805 * np.cos(obs[7]))]) * np.arctan2(obs[7], obs[11])
