# colmo best policy for pendulum: training score 183.10, held-out 183.00 after 25 samples
def policy(obs):
    action = 0.0
    return 2.38 * obs[0] + 7.15 * obs[2] - 5.66 * obs[1]