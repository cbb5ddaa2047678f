# colmo best policy for a1: training score 140.91, held-out 143.11 after 64 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = np.zeros(12) - 1.402 * (obs[6] + 0.1104 * obs[6] * obs[21])
    # coverage: `np.clip(-0.4014, -0.1307, 0.2753)`: changed 100% of 110,000 values (100% raised, 0% lowered): always at a limit
    return action + np.array([0.3548, 0.3449, -1.114, np.clip(-0.4014, -0.1307, 0.2753), -0.06981, 0.132, 0.5474, 0.09635, 0.1887, -0.7508, -0.3838, 0.2056]) * np.arctan2(obs[24], obs[23])