# colmo best policy for quadruped: training score 126.74, held-out 122.31 after 56 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: `0.1549 / obs[13]`: divisor never 0 in 110,000 values
    action = np.zeros(12) - np.array([7.408, -0.04159, -4.336, -5.69, -1.628, 0.3673 * obs[47] + 0.1549 / obs[13], 7.033, -0.2139, 2.489, -8.059, 0.8961, 5.175]) * obs[77]
    return action