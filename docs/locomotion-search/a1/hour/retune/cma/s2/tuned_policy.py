# tuned by colmo-optimize (gfo=cma): training score 154.97, held-out 151.24
import numpy as np

def policy(obs):
    action = 0.008569 * obs[21] + np.array([0.8402, 1.806 * obs[13], 0.1269, -0.3878, -0.1769, -0.471, 0.1447, 1.365, 0.1564, 0.1064, -0.4642, 1.105]) * obs[3] ** 2
    action_b = 0.03352 * obs[21] + np.array([0.6997, -0.3067, 0.1464, -0.362, -0.2355, -0.5075, 0.1253, 1.048, 0.1679, 0.2359, -0.4287, 0.8613]) * obs[3] ** 2
    return 0.4185 * action + 0.3513 * action_b
