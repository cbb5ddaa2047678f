# colmo: the best policy of pendulum simplified: training score 875.70, held-out 848.32
def policy(obs):
    if obs[0] < 0.7245:
        return obs[2]
    else:
        return -29.18 * obs[1] - 6.242 * obs[2]
