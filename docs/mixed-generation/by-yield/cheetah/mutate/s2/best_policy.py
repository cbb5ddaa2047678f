# colmo best policy for cheetah: training score 233.99, held-out 217.52 after 278 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    action = np.zeros(6) + np.array([1.209, 0.0646, 0.2563, -0.05617, -0.1442, -0.04438]) * obs[11]
    action_b = np.zeros(6) + np.array([1.306, -0.1087, 0.8444, -0.2341, 0.02879, 0.2909]) * obs[11]
    action_b = np.zeros(6) + np.array([2.516, -0.04826, 0.2206, 0.8294, 0.1262, -0.07135]) * obs[11]
    # coverage: conditional `obs[4] < 0.1394`: true 51% of 110,000 tests
    return 1.245 * (action + np.array([0.09596, -0.06408, 0.03179, -0.7767, 0.006851, 0.3012]) * obs[3] + np.array([-0.06302, -0.009394, 0.01175, -0.3134, 0.4975, -0.08244]) * obs[6] * obs[10] + np.array([0.5568, 0.2542, -0.671, 0.009375, 0.09481, -0.1005 * obs[4] - 0.07345 * obs[11]]) * np.sin(obs[10]) if obs[4] < 0.1394 else action_b + action_b + (np.array([0.1375, 0.1913, 0.1656, 0.2593, -(1.857 - 2.58 * obs[12] * obs[3]), -0.1103]) + obs[6]) * obs[10] - 0.4198 * obs[5] ** 2) + 0.08314 * (action_b + np.array([-0.07214, -0.02921, -0.03461, 0.5649, 0.05928, -0.03516]) * obs[3] + (np.array([0.007836, -0.04173, 0.2405, -0.2406, -3.517, 0.1211]) - 0.1688 * np.arctan2(obs[0], obs[6])) * obs[6] * obs[10]) + np.array([-0.4762, -0.1874, -0.2268, 0.2775, 0.1951, -0.5453]) * obs[0] * obs[7]