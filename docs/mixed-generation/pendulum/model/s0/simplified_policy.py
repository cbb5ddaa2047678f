# colmo: the best policy of pendulum simplified: training score 497.80, held-out 503.82
import numpy as np

def policy(obs):
    angle = np.arctan2(obs[1], obs[0])
    velocity = obs[2]
    angle_from_upright = angle - 1.452
    torque = angle_from_upright * (0.04995 - velocity / (np.cos(angle_from_upright) * -0.6521))
    if torque > -0.6953:
        torque = 1.104
    elif torque < -7.044:
        torque = -1.124
    return torque
