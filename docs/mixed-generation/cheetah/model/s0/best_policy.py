# colmo best policy for cheetah: training score 113.80, held-out 112.28 after 66 samples
import numpy as np

def policy(obs):
    Torque_gain = 5.414
    Spring_constant = 17.93
    Damping_constant = 0.7383
    thigh_angle = obs[2] + Spring_constant * (obs[8] / 0.5647) - Damping_constant * obs[5]
    shin_angle = obs[3] + Spring_constant * (obs[9] / -0.4572) - Damping_constant * obs[6]
    foot_angle = obs[4] + Spring_constant * (obs[10] / -0.3776) - Damping_constant * obs[7]
    torque = Torque_gain * obs[8] / 0.6958
    action = np.array([torque, torque, torque, torque, torque, torque])
    action = np.clip(action, -0.7603, 2.103)
    return action