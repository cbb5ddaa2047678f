# colmo best policy for cheetah: training score 249.18, held-out 250.19 after 210 samples
# decided by the code: `np.abs(np.arctan2(obs[1], obs[14])) < -0.06336` is never true (`np.abs(np.arctan2(obs[1], obs[14]))` is in [0, 3.142])
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = np.zeros(6) + (-4.579 + np.sin(obs[6]))
    # coverage: if `np.abs(np.arctan2(obs[1], obs[14])) < -0.06336`: true 0% of 110,000 tests (never true)
    if np.abs(np.arctan2(obs[1], obs[14])) < -0.06336:
        return action
    else:
        return action + (18.32 - 21.22 * (obs[16] - -0.06562 * np.arctan2(obs[3], obs[10]) + 1.72 * obs[1])) * np.arctan2(obs[2], np.abs(obs[8])) + np.array([1.139, -1.349, 1.458, 0.1433, -0.555, 0.3723]) * obs[11]
    # coverage: if `np.abs(np.arctan2(obs[1], obs[14])) > 0.2852`: never reached
    if np.abs(np.arctan2(obs[1], obs[14])) > 0.2852:
        action = np.zeros(6) + (6.613 + -7.351 * obs[1] * (1.915 * obs[4])) * (4.554 * action + 0.1991 * obs[2] * obs[14])
        return action
    # coverage: if `obs[3] < 0.236`: never reached
    elif obs[3] < 0.236:
        return action + -39.58 * np.arctan2(obs[2], np.abs(obs[8]))
    else:
        return 1.834 * np.cos(obs[9])