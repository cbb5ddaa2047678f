# colmo: the best policy of quadruped simplified: training score 138.94, held-out 146.33
# cut short at the finish's deadline after 3 round(s); to go on: colmo-simplify task=quadruped seed=0 "policy_file='/work/runs/loco/quadruped/noise/s0/0_+task.env.joint_noise=0.05,llm=mutate,search.max_samples=1000000,search.max_seconds=1800,search.progress=False,seed=0,task=quadruped/best_policy.py'"
import numpy as np

def policy(obs):
    action = np.array([4.83, 0.7298, -0.6589, 2.131, 2.605, 0.2379, -0.3679, 0.9213, 0.9831, -0.2615, -1.41228, -0.5284]) * np.arctan2(obs[8], 0.0)
    return action
