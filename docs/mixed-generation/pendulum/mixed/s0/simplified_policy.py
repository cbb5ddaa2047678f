# colmo: the best policy of pendulum simplified: training score 789.30, held-out 771.66
def policy(obs):
    if obs[1] ** 2 < 0.4272:
        return -23.97 * obs[0] * obs[2]
    else:
        return obs[2]
