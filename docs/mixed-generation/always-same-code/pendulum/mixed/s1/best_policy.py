# colmo best policy for pendulum: training score 725.20, held-out 665.13 after 259 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = 0.1803 * obs[2] - 0.4166 * obs[1]
    # coverage: if `np.abs(obs[2]) < 0.3671`: true 61% of 110,000 tests
    if np.abs(obs[2]) < 0.3671:
        return action + 0.3336 * np.sin(obs[0]) - (3.744 - -2.443 * np.sign(obs[2])) * (obs[1] - -1.367 * obs[2] * obs[0])
    else:
        # coverage: `np.clip(obs[0], -0.9577 - 5.961 * obs[1], 0.4369)`: changed 74% of 43,186 values (25% raised, 48% lowered)
        return action - (2.255 - 0.0476 * (np.clip(obs[0], -0.9577 - 5.961 * obs[1], 0.4369) + 0.1798 * (np.cos(obs[0]) - 3.246 * action))) * (obs[1] - -2.516 * obs[2] * obs[0]) + 5.005 * np.arctan2(obs[2], obs[1])