# colmo best policy for pendulum: training score 187.00, held-out 181.70 after 25 samples
def policy(obs):
    return -4.42 * (obs[1] - 5.32 * obs[2])