# colmo best policy for pendulum: score 842.30 after 2684 samples
import numpy as np

def policy(obs):
    return ((-5.74 + 1.75 * np.tanh(obs[0])) * (obs[1] - (-0.143 * obs[0] + 0.757 * obs[1] * obs[1] - 0.283 * obs[1] * obs[0] - 0.203 * obs[0]) * obs[2]) - 0.407 * (0.461 * obs[0] + 0.212 * obs[2]) + 0.268 * np.arctan2(obs[2], obs[0]) if obs[1] > 0.552 else -5.74 * (obs[1] - np.tanh((-0.143 * obs[0] + 0.757 * obs[1] * obs[1] - 0.203 * obs[0]) * obs[2])) - 0.407 * np.sign(obs[1]) + 0.268 * np.arctan2(obs[2], obs[0])) + 1.02 * obs[1] if np.abs(obs[1]) > 0.217 else -5.74 * (obs[1] - np.tanh((-0.143 * obs[0] + 0.757 * obs[1] * obs[1] - 0.203 * obs[0]) * obs[2])) - 0.407 * np.sign(obs[1]) + 1.02 * obs[1]
