# tuned by colmo-optimize (gfo=bo): training score 238.03, held-out 224.30
import numpy as np

def policy(obs):
    pos = obs[:3]
    vel = obs[3:6]
    ang_vel = obs[6:9]
    action = np.zeros(6)
    action[0] = -22.29 * vel[0]
    action[1] = -0.341 * ang_vel[0]
    action[2] = 3.189 * ang_vel[1]
    action[3] = -14.26 * ang_vel[2]
    action[4] = -18.97 * ang_vel[1]
    return action
