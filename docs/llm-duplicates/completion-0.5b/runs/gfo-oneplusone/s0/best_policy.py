# colmo best policy for pendulum: training score 73.20, held-out 41.77 after 48 samples
import numpy as np

def policy(obs):
    angle = np.arctan2(obs[1], obs[2])
    torque = -0.01857 * np.tanh(angle)
    torque = np.clip(torque, -1.631, -0.9283)
    return torque