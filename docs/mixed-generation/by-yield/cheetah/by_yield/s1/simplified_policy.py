# colmo: the best policy of cheetah simplified: training score 284.74, held-out 282.66
# cut short at the finish's deadline after 5 round(s); to go on: colmo-simplify task=cheetah seed=1 "policy_file='/work/runs/yield/cheetah/by_yield/s1/0_llm=llamacpp,search.fill=mutate,search.max_samples=1000000,search.max_seconds=1800,search.model_share=by_yield,search.progress=False,seed=1,task=cheetah/best_policy.py'"
import numpy as np

def policy(obs):
    action_b = np.array([-72.44, -9.537, -91.9, 0.1793, 13.4, 14.72]) * obs[3] + np.array([1.362, 2.315, 1.0, 0.07586, -0.0102, 1.41]) * np.sin(0.3306 * obs[12])
    return action_b + np.array([-0.2094, -0.3389, -0.1102, 0.01142, 0.2325, -1.775]) * np.arctan2(obs[4], obs[15])
