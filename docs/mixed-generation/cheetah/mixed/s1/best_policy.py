# colmo best policy for cheetah: training score 175.86, held-out 158.14 after 288 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = np.zeros(6) - (-2.944 * obs[14] + 1.159 * obs[15] - -2.457 - (np.sin(obs[6]) + 0.9223 * np.sign(obs[1])))
    action_b = np.zeros(6) - (1.241 - (obs[6] + -0.08646 * np.sin(obs[3])))
    # coverage: conditional `obs[9] > -0.1058`: true 53% of 110,000 tests
    return action if obs[9] > -0.1058 else action_b