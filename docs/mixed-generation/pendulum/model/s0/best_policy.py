# colmo best policy for pendulum: training score 491.20, held-out 466.54 after 140 samples
import numpy as np

def policy(obs):
    angle = np.arctan2(obs[1], obs[0])
    velocity = obs[2]
    angle_from_upright = angle - np.pi / 2.249
    angular_velocity = velocity
    torque = angle_from_upright * (0.01908 - velocity / (np.cos(angle_from_upright) * -0.9338))
    if torque > -0.6337:
        torque = 1.195
    elif torque < -5.576:
        torque = -0.8286
    return torque