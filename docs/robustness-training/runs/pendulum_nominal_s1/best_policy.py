# colmo best policy for pendulum: training score 101.90, held-out 1.70 after 25 samples
def policy(obs):
    action = 0.0
    return action - 6.89 * action - 5.66 * obs[1]