# colmo best policy for pendulum: training score 674.10, held-out 649.33 after 303 samples
# branches counted over 110 training and held-out episodes (fast path)
import numpy as np

def policy(obs):
    # coverage: if `obs[2] < 0.1245`: true 56% of 110,000 tests
    if obs[2] < 0.1245:
        action = -(-0.4312 * obs[2] - 5.427 * (obs[0] - 0.7573 * np.sin(obs[0])))
    else:
        # coverage: `np.clip(-(-1.315 * obs[2] - 6.836 * (obs[0] - 2.066 * np....`: changed 35% of 48,069 values (0% raised, 35% lowered)
        action = np.clip(-(-1.315 * obs[2] - 6.836 * (obs[0] - 2.066 * np.sin(obs[0]))) + 1.071 * obs[1], -5.33, 0.1235)
    # coverage: if `obs[2] < 0.1123 - 1.283 * obs[1] ** 2`: true 47% of 110,000 tests
    if obs[2] < 0.1123 - 1.283 * obs[1] ** 2:
        action_b = -(-0.5343 * obs[2] - 5.178 * (obs[0] - 0.7573 * np.sin(obs[0])))
    else:
        action_b = -(-0.7586 * obs[2] - 6.139 * (obs[0] - 2.61 * np.sin(obs[0]))) + 1.608 * obs[1]
    # coverage: conditional `np.abs(action) < 1.806`: true 29% of 110,000 tests
    return action - 12.84 * np.arctan2(obs[1] - 136.5 * action, obs[2]) if np.abs(action) < 1.806 else action_b - 22.32 * np.arctan2(obs[1] - 98.56 * action_b, obs[2])