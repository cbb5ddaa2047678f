# colmo best policy for cheetah: training score 251.19, held-out 242.55 after 137 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = 2.189 * np.tanh(obs[7]) + np.array([-0.2847, -0.217 + 0.131 * np.sign(obs[6]), 0.5667, -1.907, -0.2308, 0.3124]) * obs[7] * obs[9]
    action = 0.8184 * np.tanh(obs[7])
    # coverage: if `obs[1] < -0.9703`: true 0% of 110,000 tests (never true)
    if obs[1] < -0.9703:
        action = np.zeros(6)
    else:
        action = np.zeros(6) + 0.1899 * obs[0]
    return action + np.array([-0.05216, -0.1128, -0.8684, 0.05027, -0.9584, -0.9899]) * np.sign(obs[2]) + np.array([0.5456, -0.1524, -0.2046, 0.534, -0.3121, -(0.805 * np.cos(obs[7]))]) * np.arctan2(obs[7], obs[11])