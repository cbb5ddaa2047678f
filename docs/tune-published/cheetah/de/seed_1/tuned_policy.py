# tuned by colmo-optimize (gfo=de): training score 257.33, held-out 246.89
import numpy as np

def policy(obs):
    pos = obs[:3]
    vel = obs[3:6]
    ang_vel = obs[6:9]
    action = np.zeros(6)
    action[0] = -18.55 * vel[0]
    action[1] = -0.3138 * ang_vel[0]
    action[2] = 3.62 * ang_vel[1]
    action[3] = -0.3294 * ang_vel[2]
    action[4] = -12.27 * ang_vel[1]
    return action
