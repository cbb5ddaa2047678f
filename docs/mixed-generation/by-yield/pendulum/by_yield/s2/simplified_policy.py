# colmo: the best policy of pendulum simplified: training score 785.60, held-out 847.21
def policy(obs):
    action = 26.67 * obs[2]
    if obs[0] < 0.7568:
        action_b = obs[2]
    else:
        action_b = -3.02 * obs[1]
    return 0.1903 * action + 4.88 * (action_b - 1.765 * obs[2])
