# tuned by colmo-optimize (gfo=cma): training score 210.02, held-out 201.15
import numpy as np

def policy(obs):
    pos = obs[:3]
    vel = obs[3:6]
    ang_vel = obs[6:9]
    action = np.zeros(6)
    action[0] = -12.241 * vel[0]
    action[1] = -0.603 * ang_vel[0]
    action[2] = 11.351 * ang_vel[1]
    action[3] = -8.106 * ang_vel[2]
    action[4] = -12.268 * ang_vel[1]
    return action
