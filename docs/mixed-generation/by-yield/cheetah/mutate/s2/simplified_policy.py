# colmo: the best policy of cheetah simplified: training score 236.10, held-out 220.96
# cut short at the finish's deadline after 5 round(s); to go on: colmo-simplify task=cheetah seed=2 "policy_file='/work/runs/yield/cheetah/mutate/s2/0_llm=mutate,search.max_samples=1000000,search.max_seconds=1800,search.progress=False,seed=2,task=cheetah/best_policy.py'"
import numpy as np

def policy(obs):
    action = np.array([1.209, 0.0646, 0.2563, -0.05617, -0.1442, -0.04438]) * obs[11]
    action_b = np.zeros(6) + np.array([2.516, -0.04826, 0.2206, 0.8294, 0.1262, -0.07135]) * obs[11]
    return 1.245 * (action + np.array([0.09596, -0.06408, 0.03179, -0.7767, 0.006851, 0.3012]) * obs[3] + np.array([-0.06302, -0.009394, 0.01175, -0.3134, 0.4975, -0.08244]) * obs[6] * obs[10] if obs[4] < 0.1394 else action_b + action_b + (np.array([0.1375, 0.1913, 0.1656, 0.2593, -(1.857 - 2.58 * obs[12] * obs[3]), -0.1103]) + obs[6]) * obs[10] - 0.4198 * obs[5] ** 2) + 0.08314 * (action_b + np.array([-0.07214, -0.02921, -0.03461, 0.5649, 0.05928, -0.03516]) * obs[3])
