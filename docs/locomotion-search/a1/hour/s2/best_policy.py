# colmo best policy for a1: training score 150.63, held-out 151.30 after 187 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = np.zeros(12) * (-0.3975 * obs[4] * (-0.3037 * np.arctan2(obs[5], obs[23])))
    action = np.zeros(12) + 0.0162 * obs[21] + np.array([0.9069, -0.2638 + 2.143 * obs[13], 0.13, -0.3416, -0.2213, -0.5207, 0.1489, 1.005, 0.1634, 0.1417, -0.4442, 0.9165]) * obs[3] ** 2
    # coverage: `np.clip(obs[17], -0.2582, 3.656)`: changed 51% of 110,000 values (40% raised, 11% lowered)
    action_b = np.zeros(12) * (np.array([0.4034 + 4.008 * np.arctan2(obs[2], obs[4]), 0.5383, 0.627, 0.6252, -0.1315, -0.1769, 0.1296, -0.3469, -0.3271, 0.4859, -0.8709, -0.2629]) * np.cos(np.clip(obs[17], -0.2582, 3.656)))
    action_b = np.zeros(12) + 0.0146 * obs[21] + np.array([0.8374, -0.303, 0.1259, -0.3418, -0.2553, -0.5607, 0.1199, 0.8434, 0.1395, 0.1517, -0.5424, 0.8156]) * obs[3] ** 2
    return 0.5068 * action + 0.4948 * action_b