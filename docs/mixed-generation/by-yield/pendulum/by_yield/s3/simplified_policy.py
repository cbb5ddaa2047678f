# colmo: the best policy of pendulum simplified: training score 819.50, held-out 850.42
def policy(obs):
    return 3.809 * ((-2.389 * obs[1] + -4.228 * obs[2]) * obs[0] + 3.249 * obs[2])
