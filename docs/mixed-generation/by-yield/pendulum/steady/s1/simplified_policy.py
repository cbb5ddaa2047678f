# colmo: the best policy of pendulum simplified: training score 852.10, held-out 530.82
# cut short at the finish's deadline after 7 round(s); to go on: colmo-simplify task=pendulum seed=1 "policy_file='/work/runs/yield/pendulum/steady/s1/0_llm=mutate,search.max_samples=1000000,search.max_seconds=1800,search.progress=False,search.steady_state=True,seed=1,task=pendulum/best_policy.py'"
import numpy as np

def policy(obs):
    if obs[2] > -(-0.08264 + 11.79 * np.arctan2(obs[1], obs[2])):
        action_b = 0.2401 - 0.3457 * obs[1] * obs[0]
    else:
        action_b = -1.43 * (obs[1] + 3.042 * obs[0])
    return 1.476 * obs[2] - 3.122 * action_b - 0.08021 * obs[1] + 5.521 * ((0.147 - (0.787 - 0.8145 * np.clip(obs[1], -0.2031, 6.031)) * np.tanh(obs[2])) * obs[1]) - 5.521 * np.tanh(4.822 * obs[0] - 0.6376 * obs[2])
