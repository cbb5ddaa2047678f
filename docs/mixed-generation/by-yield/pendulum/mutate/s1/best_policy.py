# colmo best policy for pendulum: training score 874.30, held-out 852.07 after 266 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `obs[0] < 0.5795`: true 13% of 110,000 tests
    if obs[0] < 0.5795:
        return obs[0] ** 2 * obs[1] - -21.28 * obs[2] - 0.9036 * obs[2] + (4.179 * np.arctan2(obs[1], obs[2]) + -0.481 * np.sin(obs[0]))
    else:
        return -42.47 * obs[1] - (7.143 * obs[2] + -2.08 * obs[0])
    return obs[0] ** 2 * obs[1] - 77.18 * obs[2] - 2.156 * obs[2] + -2.023 * np.arctan2(obs[1], obs[2])