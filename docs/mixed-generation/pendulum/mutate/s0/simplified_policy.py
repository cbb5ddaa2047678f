# colmo: the best policy of pendulum simplified: training score 857.80, held-out 847.74
def policy(obs):
    if obs[0] > 0.7204:
        action_b = -(19.17 * obs[1] + 3.402 * obs[2])
    else:
        action_b = -(-4.626 * obs[2])
    return action_b
