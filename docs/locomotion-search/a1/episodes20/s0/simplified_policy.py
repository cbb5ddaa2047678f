# colmo: the best policy of a1 simplified: training score 131.55, held-out 131.49
# cut short at the finish's deadline after 6 round(s); to go on: colmo-simplify task=a1 seed=0 "policy_file='/work/runs/a1e20/a1/episodes20/s0/0_llm=mutate,search.max_samples=1000000,search.max_seconds=3600,search.progress=False,seed=0,task.episodes=20,task=a1/best_policy.py'"
import numpy as np

def policy(obs):
    if obs[7] * obs[19] < 3.258:
        action = np.array([1.075, 0.1265, -0.02818, 0.6952, 2.194, 0.3908, 1.0, -0.1806, 0.1994, 0.1131, 0.03735, 0.1907]) * np.sign(obs[13])
    else:
        action = np.zeros(12) - 19.02 * obs[22] * obs[16]
    action_b = np.zeros(12) - (0.1147 + obs[26])
    return action if np.abs(obs[20]) < 0.2988 else action_b
