# colmo: the best policy of cheetah simplified: training score 212.49, held-out 195.59
def policy(obs):
    action = [17.91, 0.1567, 3.046, 0.7085, -0.6327, -9.721] / obs[11]
    return action - 0.04194 * obs[13] + -0.9219 * obs[4]
