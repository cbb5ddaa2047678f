# colmo best policy for cheetah: training score 212.49, held-out 195.59 after 223 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: `np.array([17.91, 0.1567, 3.046, 0.7085, -0.6327, -9.721])...`: divisor never 0 in 660,000 values
    action = np.zeros(6) + np.array([17.91, 0.1567, 3.046, 0.7085, -0.6327, -9.721]) / obs[11]
    return action - 0.04194 * obs[13] + -0.9219 * obs[4]