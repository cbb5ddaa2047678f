# colmo: the best policy of quadruped simplified: training score 110.39, held-out 112.73
# cut short at the finish's deadline after 1 round(s); to go on: colmo-simplify task=quadruped seed=0 "policy_file='/work/runs/quadcma/quadruped/cma_noise/s0/0_+task.env.joint_noise=0.05,gfo=cma,llm=mutate,search.max_samples=1000000,search.max_seconds=1800,search.progress=False,seed=0,task=quadruped/best_policy.py'"
import numpy as np

def policy(obs):
    action = np.zeros(12) + np.array([0.9247, 0.1891, 0.08064, 0.6421, -0.4598, 0.2602, -0.273, 0.2542, 0.1762, 0.2903, -0.2375 + 2.143 * np.abs(obs[53]), -0.1548]) * np.arctan2(obs[8], obs[63]) - 0.2931 * np.eye(12)[1] * obs[15] * obs[1]
    return action
