# colmo best policy for pendulum: training score 576.70, held-out 505.62 after 307 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `obs[2] < -0.3606`: true 31% of 110,000 tests
    if obs[2] < -0.3606:
        action = -0.6589
    else:
        # coverage: `3.451 / np.arctan2(obs[1] - 0.9561 * obs[1], obs[0])`: divisor never 0 in 75,644 values
        action = -((0.4014 - 0.1487 * np.tanh(-0.554)) * obs[1] + 0.6432 * np.arctan2(obs[1], obs[2]) + -0.986 * obs[2]) - 3.451 / np.arctan2(obs[1] - 0.9561 * obs[1], obs[0])
        action = 1.387 + -2.62 * obs[0]
    # coverage: if `np.abs(np.arctan2(obs[1], obs[0])) > 0.106`: true 83% of 110,000 tests
    if np.abs(np.arctan2(obs[1], obs[0])) > 0.106:
        return action
    else:
        return 1.865 * obs[1]