# colmo best policy for cheetah: training score 208.03, held-out 156.48 after 232 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `obs[1] < -1.085`: true 25% of 110,000 tests
    if obs[1] < -1.085:
        action = -1.187 * np.abs(obs[6]) * np.tanh(obs[10])
    else:
        action = -0.6885 * np.sign(obs[6])
    return action + np.array([-1.185, -0.07275, -2.475, 0.571, 0.1517, 0.08173 - 4.915 * obs[10]]) * np.arctan2(obs[3], obs[2])