# colmo: the best policy of pendulum simplified: training score 679.10, held-out 648.93
# cut short at the finish's deadline after 6 round(s); to go on: colmo-simplify task=pendulum seed=0 "policy_file='/work/runs/yield/pendulum/steady/s0/0_llm=mutate,search.max_samples=1000000,search.max_seconds=1800,search.progress=False,search.steady_state=True,seed=0,task=pendulum/best_policy.py'"
import numpy as np

def policy(obs):
    if obs[2] < 0.1245:
        action = -(-0.4312 * obs[2] - 5.427 * (obs[0] - 0.63724597679502))
    else:
        action = np.clip(-(-1.315 * obs[2] - 6.836 * (obs[0] - 2.066 * np.sin(obs[0]))) + 1.071 * obs[1], -5.33, 0.1235)
    if obs[2] < 0.1123 - 1.283 * obs[1] ** 2:
        action_b = -(-0.5343 * obs[2] - 5.178 * obs[0])
    else:
        action_b = -1.0 + 1.608 * obs[1]
    return action - 12.84 * (obs[1] - 136.5 * action) if np.abs(action) < 1.806 else action_b - 22.32 * (obs[1] - 98.56 * action_b)
