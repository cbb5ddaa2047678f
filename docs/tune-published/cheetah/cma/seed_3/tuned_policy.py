# tuned by colmo-optimize (gfo=cma): training score 248.81, held-out 233.59
import numpy as np

def policy(obs):
    pos = obs[:3]
    vel = obs[3:6]
    ang_vel = obs[6:9]
    action = np.zeros(6)
    action[0] = -8.137 * vel[0]
    action[1] = -0.5434 * ang_vel[0]
    action[2] = 2.728 * ang_vel[1]
    action[3] = -6.057 * ang_vel[2]
    action[4] = -8.781 * ang_vel[1]
    return action
