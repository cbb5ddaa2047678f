# colmo best policy for cheetah: training score 251.74, held-out 244.23 after 770 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = 1.09 * obs[9]
    # coverage: `np.clip(-68.63 - 4.338 * obs[3], -62.84, 0.1864)`: changed 100% of 110,000 values (100% raised, 0% lowered): always at a limit
    return np.sin(action) + np.array([37.48, 1.642, 8.868, 7.033, -np.clip(-68.63 - 4.338 * obs[3], -62.84, 0.1864), 341.6]) * obs[1]