# colmo best policy for pendulum: training score 791.60, held-out 523.87 after 568 samples
# decided by the code: `np.sin(obs[1]) > -3.173` is always true (`np.sin(obs[1])` is in [-1, 1])
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `np.sin(obs[1]) > -3.173`: true 100% of 110,000 tests (always true)
    if np.sin(obs[1]) > -3.173:
        # coverage: `-0.3833 / (obs[1] + (-1.349 + 3.69 * obs[0]) * obs[0] * (...`: divisor never 0 in 110,000 values
        # coverage: `-0.1995 / (obs[1] + 0.238 * obs[0] * obs[2])`: divisor never 0 in 110,000 values
        return 0.6124 * (-0.3833 / (obs[1] + (-1.349 + 3.69 * obs[0]) * obs[0] * (-0.1064 * obs[2] + 1.831 * obs[1])) + 0.591 * obs[0] + obs[2] + 3.021 * (np.arctan2(obs[1], obs[2]) - (obs[1] + -1.226 * obs[1]))) + 2.21 * (-0.1995 / (obs[1] + 0.238 * obs[0] * obs[2]) + obs[2])
    else:
        return 14.31 * np.tanh(obs[0])