# colmo best policy for pendulum: training score 834.50, held-out 822.34 after 358 samples
# decided by the code: `np.abs(np.abs(obs[0])) > -0.06229` is always true (`np.abs(np.abs(obs[0]))` is in [0, 1])
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `np.sin(obs[0]) < 0.692`: true 16% of 110,000 tests
    if np.sin(obs[0]) < 0.692:
        action = 18.64 * obs[2] + 9.912 * obs[1]
    # coverage: if `obs[2] > -3.228`: true 100% of 91,990 tests
    elif obs[2] > -3.228:
        action = -14.56 * obs[2] + -16.11 * obs[1] - 5.215 * np.abs(obs[2])
    else:
        action = -1.109 * np.cos(obs[2])
    # coverage: if `np.abs(np.abs(obs[0])) > -0.06229`: true 100% of 110,000 tests (always true)
    if np.abs(np.abs(obs[0])) > -0.06229:
        return action
    else:
        return action - 0.3287 * obs[2] ** 2