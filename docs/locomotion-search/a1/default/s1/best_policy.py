# colmo best policy for a1: training score 146.50, held-out 140.16 after 170 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = np.zeros(12)
    # coverage: `np.clip(action, -2.642, 1.501)`: changed 0% of 1,320,000 values (0% raised, 0% lowered)
    return np.clip(action, -2.642, 1.501) - -0.04465 * (obs[22] - 0.3792 * np.arctan2(-0.4057 * np.abs(obs[13]), obs[16]))