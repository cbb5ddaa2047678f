# tuned by colmo-optimize (gfo=oneplusone): training score 221.01, held-out 235.72
import numpy as np

def policy(obs):
    pos = obs[:3]
    vel = obs[3:6]
    ang_vel = obs[6:9]
    action = np.zeros(6)
    action[0] = -35.91 * vel[0]
    action[1] = -0.2828 * ang_vel[0]
    action[2] = 3.622 * ang_vel[1]
    action[3] = -8.136 * ang_vel[2]
    action[4] = -16.8 * ang_vel[1]
    return action
