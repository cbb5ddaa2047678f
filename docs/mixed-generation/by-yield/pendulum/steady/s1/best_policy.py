# colmo best policy for pendulum: training score 852.10, held-out 533.84 after 423 samples
# decided by the code: `np.abs(obs[0] ** 2) < -0.3685` is never true (`np.abs(obs[0] ** 2)` is in [0, 1])
# decided by the code: `np.abs(obs[0] ** 2) < -0.6487` is never true (`np.abs(obs[0] ** 2)` is in [0, 1])
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `np.abs(obs[0] ** 2) < -0.3685`: true 0% of 110,000 tests (never true)
    if np.abs(obs[0] ** 2) < -0.3685:
        # coverage: if `obs[2] < -0.2118`: never reached
        if obs[2] < -0.2118:
            # coverage: `np.clip(obs[1], -0.03774, -0.3611)`: never reached
            action_b = (0.06352 - (-0.00575 - 0.09513 * np.clip(obs[1], -0.03774, -0.3611)) * np.tanh(obs[2])) * obs[1] - 0.1061 * (0.01978 * obs[0] + -16.48 * obs[2])
        else:
            action_b = 7.984 * np.sign(obs[0])
            # coverage: if `np.abs(obs[0] ** 2) < -0.6487`: never reached
            if np.abs(obs[0] ** 2) < -0.6487:
                # coverage: if `obs[2] < -0.0811`: never reached
                if obs[2] < -0.0811:
                    # coverage: `np.clip(obs[1], 0.02959, -0.4644)`: never reached
                    action_b = (0.09055 - (0.04306 - 0.05469 * np.clip(obs[1], 0.02959, -0.4644)) * np.tanh(obs[2])) * obs[1] - 0.131 * (-0.03077 * obs[0] + -11.74 * obs[2])
                else:
                    action_b = 12.77 * np.sign(obs[0])
            # coverage: if `obs[1] > 0.2281`: never reached
            elif obs[1] > 0.2281:
                action_b = -0.3692 * obs[0] - -0.05155 * obs[2]
            else:
                action_b = 7.492 * obs[1] - 2.273 * obs[0]
    # coverage: if `obs[1] > 0.6465`: true 14% of 110,000 tests
    elif obs[1] > 0.6465:
        action_b = -0.1312 * obs[0] - -0.009304 * obs[2]
    else:
        action_b = 13.68 * obs[1] - 1.193 * obs[0]
    # coverage: if `obs[2] > 1.164 * obs[2]`: true 66% of 110,000 tests
    if obs[2] > 1.164 * obs[2]:
        action = -0.068 - 0.8023 * obs[1] * obs[0]
    # coverage: if `obs[0] > -0.2431`: true 84% of 37,348 tests
    elif obs[0] > -0.2431:
        action = -2.881 * (obs[1] + 7.659 * obs[0])
    else:
        action = -0.1351 * obs[2]
    # coverage: if `obs[2] > -(-0.08264 + 11.79 * np.arctan2(obs[1], obs[2]))`: true 53% of 110,000 tests
    if obs[2] > -(-0.08264 + 11.79 * np.arctan2(obs[1], obs[2])):
        action_b = 0.2401 - 0.3457 * obs[1] * obs[0]
    else:
        action_b = -1.43 * (obs[1] + 3.042 * obs[0])
    # coverage: `np.clip(obs[1], -0.2031, 6.031)`: changed 23% of 110,000 values (23% raised, 0% lowered)
    action_b_b = (0.147 - (0.787 - 0.8145 * np.clip(obs[1], -0.2031, 6.031)) * np.tanh(obs[2])) * obs[1] - np.tanh(-0.3415 * (-14.12 * obs[0] + 1.867 * obs[2]))
    return 0.1025 * (2.841 * obs[2] + (-3.827 * action_b - -0.2716 * action)) + 0.5001 * (2.369 * obs[2] + (11.04 * action_b_b - 5.459 * action_b))