# colmo best policy for pendulum: training score 728.10, held-out 740.90 after 342 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = 2.524
    # coverage: `-(0.9708 + 1.911 * action) / obs[0]`: divisor never 0 in 110,000 values
    return np.arctan2(obs[2], obs[1]) - -4.253 * np.arctan2(-(0.9708 + 1.911 * action) / obs[0] - 4.241 * np.arctan2(obs[2], obs[1]) + obs[0], obs[2]) * np.arctan2(obs[0], obs[2])