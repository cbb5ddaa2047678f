# colmo: the best policy of quadruped simplified: training score 50.88, held-out 52.56
# cut short at the finish's deadline after 2 round(s); to go on: colmo-simplify task=quadruped seed=0 "policy_file='/work/runs/qretune/quadruped/finish_retune/s0/0_+task.env.joint_noise=0.05,finish.retune_budget=1000,llm=mutate,search.max_samples=1000000,search.max_seconds=1800,search.progress=False,seed=0,task=quadruped/best_policy.py'"
import numpy as np

def policy(obs):
    action = np.zeros(12) + np.array([0.5686, 0.7268, -1.885, 4.872, -2.341, -2.813, -1.846, -2.997, -1.226, -1.598, 5.985, 3.119]) * obs[51]
    return action + np.array([0.03904, -3.192, 0.5288, 1.774, -0.06358, -0.4238, 6.136, -1.015, -1.611, -0.8795, 0.7322, 1.657])
