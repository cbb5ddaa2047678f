# colmo best policy for pendulum: training score 643.00, held-out 729.60 after 246 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: `407.9 / (70.04 / (-0.3602 * obs[1] - np.abs(-(2.247 + -0....`: divisor never 0 in 110,000 values
    # coverage: `70.04 / (-0.3602 * obs[1] - np.abs(-(2.247 + -0.04558 * o...`: divisor never 0 in 110,000 values
    return 407.9 / (70.04 / (-0.3602 * obs[1] - np.abs(-(2.247 + -0.04558 * obs[0] - 0.4124 * np.arctan2(obs[2], obs[0])) * obs[2])) * obs[1] - -(3.86 + -0.4163 * (13.9 * obs[0]) - 0.3201 * (np.arctan2(obs[2], obs[0]) - 1.915 * obs[2] * obs[1])) * obs[2]) + (1.898 * obs[0] + 2.135 * obs[1]) * np.sin(obs[0]) + 0.9255 * obs[1]