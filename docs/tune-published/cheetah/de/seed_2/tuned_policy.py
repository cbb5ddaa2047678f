# tuned by colmo-optimize (gfo=de): training score 239.09, held-out 241.02
import numpy as np

def policy(obs):
    pos = obs[:3]
    vel = obs[3:6]
    ang_vel = obs[6:9]
    action = np.zeros(6)
    action[0] = -15.04 * vel[0]
    action[1] = -0.3831 * ang_vel[0]
    action[2] = 3.348 * ang_vel[1]
    action[3] = -6.901 * ang_vel[2]
    action[4] = -11.19 * ang_vel[1]
    return action
