# colmo best policy for pendulum: training score 839.70, held-out 670.93 after 238 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = 0.1671
    # coverage: if `np.abs(obs[2]) + -4.507 * obs[0] < -0.5389`: true 72% of 110,000 tests
    if np.abs(obs[2]) + -4.507 * obs[0] < -0.5389:
        return action - (11.97 - -0.04676 * obs[0]) * (obs[1] - -2.005 * obs[2] * obs[0]) + 0.3294 * np.arctan2(obs[2], obs[1])
        return (0.2538 * obs[2] + -0.4987 * obs[2] + -0.1671 * (-3.41 * obs[0] + -36.08 * obs[2])) * ((-0.5303 * obs[0] - 1.779 * obs[2]) * (np.cos(obs[1]) - -5.89 * obs[2] * obs[0]))
    else:
        return action - (-0.3024 - -0.07962) * (obs[1] - -6.798 * (-11.19 * obs[1] + 0.3528 * obs[0]) * obs[0]) + 17.46 * np.arctan2(obs[2], obs[1])