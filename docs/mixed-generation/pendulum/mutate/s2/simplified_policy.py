# colmo: the best policy of pendulum simplified: training score 786.10, held-out 846.04
def policy(obs):
    action = obs[2]
    if 5.12 * obs[0] < 3.926:
        return action
    else:
        return -1.982 * obs[2] - 10.52 * obs[1]
