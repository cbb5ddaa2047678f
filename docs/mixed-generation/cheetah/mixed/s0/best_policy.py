# colmo best policy for cheetah: training score 179.54, held-out 144.71 after 310 samples
import numpy as np

def policy(obs):
    action = -11.98 * obs[1]
    if np.abs(obs[0] ** 2) > -0.15:
        action = np.clip(np.zeros(6), -232.4 * obs[16] - 11.65 * obs[9] + 144.3 * obs[3], -16.78) - -42.08 * obs[0]
    else:
        action_b_b = np.zeros(6)
        action = -2.253 * obs[6]
    if obs[4] < 0.8329:
        action_b = np.clip(np.zeros(6), 0.07659 * np.cos(np.sin(np.arctan2(obs[3], np.clip(np.zeros(6), -0.5225 * obs[5] + 0.1686 * obs[9], 2.396) - 1.776 * obs[4] - -(2.398 * obs[12]) * obs[0]))), -0.1) - -305.9 * obs[0]
    else:
        action_b = np.clip(np.zeros(6), 0.09058 * np.cos(np.sin(np.arctan2(obs[3], np.clip(np.zeros(6), -0.3461 * obs[5] + 0.1187 * obs[9], 2.28) - -(10.94 * obs[12]) * obs[0]))), -0.7144) - -1749.0 * obs[0] - 0.1986 * obs[6]
    return -251.5 * obs[9] * action + (0.2308 + -126.4 * obs[14]) * action_b