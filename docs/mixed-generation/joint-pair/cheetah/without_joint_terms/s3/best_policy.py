# colmo best policy for cheetah: training score 316.43, held-out 291.79 after 216 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = np.zeros(6)
    action = np.zeros(6)
    # coverage: `np.array([-10.08, -0.01127, -0.1144, -0.01725, 0.274, -0....`: divisor never 0 in 660,000 values
    return action - 0.1838 * obs[3] + np.array([-10.08, -0.01127, -0.1144, -0.01725, 0.274, -0.1518 * obs[1]]) / np.tanh(obs[3])