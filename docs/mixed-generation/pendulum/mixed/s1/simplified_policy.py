# colmo: the best policy of pendulum simplified: training score 876.90, held-out 838.06
def policy(obs):
    if obs[0] < 0.7899:
        return obs[2]
    else:
        return -2.662 * obs[2] + -13.03 * obs[1]
