# colmo best policy for quadruped: training score 143.72, held-out 143.72 after 104 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = np.zeros(12) + np.array([-0.4373, 0.962, -1.509 * (obs[51] + 0.703 * obs[65]) - 1.192 * obs[25], 0.4516, -0.8288, -0.2021, -2.096, -0.01913, 1.66, 0.6851, 1.47, -0.7158]) * np.sign(obs[5])
    # coverage: `np.clip(-0.08488, -0.779, 0.558)`: changed 0% of 110,000 values (0% raised, 0% lowered)
    return action + np.array([0.9641, -0.1164, -3.531 - 4.644 * np.arctan2(obs[7], obs[1]), 1.684, -0.978, 0.04774, 1.284, -0.971, -0.9734, np.clip(-0.08488, -0.779, 0.558), 1.129, -4.993]) * np.tanh(obs[77])