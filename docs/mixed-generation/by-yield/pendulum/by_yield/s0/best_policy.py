# colmo best policy for pendulum: training score 858.50, held-out 836.67 after 358 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = np.sign((0.1618 - 3.951 * np.cos(obs[1])) * obs[1] - 0.6503 * obs[2])
    # coverage: if `obs[0] > 0.7659`: true 85% of 110,000 tests
    if obs[0] > 0.7659:
        return action + 0.2885 * np.cos(obs[0] + 2.347 * obs[2])
    else:
        return action + -0.8754 * action - (-0.8602 - 1.283 * obs[0] * obs[2] - 3.824 * obs[2])