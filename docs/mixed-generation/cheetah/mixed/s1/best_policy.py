# colmo best policy for cheetah: training score 229.46, held-out 213.77 after 554 samples
import numpy as np

def policy(obs):
    if np.sin(obs[10]) < 1.551:
        if obs[5] > -2.586:
            action = np.zeros(6) * (-0.336 * obs[12]) - 1.912 * obs[11]
        else:
            action = 1.312 * np.arctan2(obs[9], obs[3])
        action_b = np.zeros(6) + -3.034 * (obs[16] + 12.33 * obs[16] * obs[2]) - (68.96 - obs[11])
    else:
        action = np.zeros(6) + -0.4184 * obs[12] - 28.42 * obs[11] - 0.5348 * obs[4]
    action_b = np.zeros(6) + 0.1716 * (obs[16] + -7.43 * obs[2]) - 131.4 * obs[11]
    if obs[12] > -3.025:
        return 0.5637 * np.clip(action, 192.4 * obs[1] * obs[11], 74.67 * (0.1854 * obs[5] + 0.02488 * obs[15]) / (obs[11] - 0.5392 * np.arctan2(obs[14], obs[1]) * np.sign(np.arctan2(obs[4], obs[10])))) + 20.15 * (np.clip(action_b, 42.17 * obs[1] * obs[11], 111.7 * np.cos(obs[1]) * obs[11]) - 0.1901 * obs[7] / obs[8])
    else:
        return 1.048 * action