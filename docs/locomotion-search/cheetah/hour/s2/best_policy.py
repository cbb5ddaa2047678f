# colmo best policy for cheetah: training score 282.70, held-out 276.60 after 574 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `obs[5] < -(0.2085 + 10.75 * obs[15])`: true 57% of 110,000 tests
    if obs[5] < -(0.2085 + 10.75 * obs[15]):
        action = np.zeros(6)
    else:
        action = np.zeros(6) - (0.04706 * obs[8] + 8.413 * (-0.9117 * obs[11] * obs[9]) ** 2)
    # coverage: if `obs[5] < -0.1976`: true 52% of 110,000 tests
    if obs[5] < -0.1976:
        action = np.zeros(6) + np.array([-0.1683, -0.3634, 0.4631, 0.1997, -0.2537, 0.1347]) * obs[8] + np.array([0.1699, 0.5493, -0.1622, 0.2502, 0.1164, 0.442]) * np.arctan2(obs[2], obs[9])
    else:
        action = np.zeros(6) - (0.1559 * obs[8] + 2.769 * obs[0] ** 2)
    # coverage: `np.clip(action, 0.4986, 0.3349)`: changed 100% of 660,000 values (78% raised, 22% lowered): always at a limit
    return np.clip(action, 0.4986, 0.3349) * (np.array([-0.2635, 3.418 + 0.1349 * obs[11], -1.276, 0.04249, 0.5516, 0.08842]) * obs[12]) + np.array([-0.02676, 0.2746, -0.2541, -0.6242, 0.5045, -0.0456]) * np.arctan2(obs[2], obs[15])