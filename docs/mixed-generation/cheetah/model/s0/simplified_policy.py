# colmo: the best policy of cheetah simplified: training score 113.80, held-out 112.28
import numpy as np

def policy(obs):
    Torque_gain = 5.414
    torque = Torque_gain * obs[8] / 0.6958
    action = [torque, torque, torque, torque, torque, torque]
    action = np.clip(action, -0.7603, 2.103)
    return action
