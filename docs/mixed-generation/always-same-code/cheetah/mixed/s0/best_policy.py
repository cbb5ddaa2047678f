# colmo best policy for cheetah: training score 301.45, held-out 310.61 after 247 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = np.zeros(6)
    # coverage: if `np.abs(obs[6]) < 0.9056`: true 100% of 110,000 tests (always true)
    if np.abs(obs[6]) < 0.9056:
        return action + np.array([-21.28, -1.558, -5.349, 0.4344, 13.56, 1.517]) * obs[3]
    else:
        return action + np.abs(np.array([-53.78, -2.829, -48.2, 1.148, 5.065, -2.864]) * obs[3]) - 0.1929 * np.sign(obs[4])