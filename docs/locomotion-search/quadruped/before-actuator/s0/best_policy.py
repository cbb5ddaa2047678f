# colmo best policy for quadruped: training score 20.99, held-out 20.99 after 156 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `np.abs(obs[66]) > -1.936`: true 100% of 110,000 tests (always true)
    if np.abs(obs[66]) > -1.936:
        action = np.zeros(12) + 10.63 * (obs[21] ** 2 + 0.6771 * np.sin(obs[18]) * np.arctan2(obs[21], obs[27]))
    # coverage: if `np.abs(obs[24] ** 2) < 1.506`: never reached
    elif np.abs(obs[24] ** 2) < 1.506:
        action = np.zeros(12) + 3.768 * (obs[21] ** 2 + -2.098 * np.sin(obs[18]) * np.arctan2(obs[21], obs[27])) - 5.026 * np.sin(obs[51])
    else:
        action = np.zeros(12) + 3.75 * (obs[21] ** 2 + -2.784 * np.sin(obs[18]) * np.arctan2(obs[21], obs[27])) - 3.792 * np.sin(obs[51]) + 1.93 * obs[67] ** 2
    action_b = np.zeros(12) - 8.982 * (-16.98 * obs[53] - -1.288 * obs[29])
    return 0.787 * action + -2.846 * action_b