# tuned by colmo-optimize (gfo=cma): training score 259.06, held-out 240.83
import numpy as np

def policy(obs):
    pos = obs[:3]
    vel = obs[3:6]
    ang_vel = obs[6:9]
    action = np.zeros(6)
    action[0] = -25.62 * vel[0]
    action[1] = -0.3645 * ang_vel[0]
    action[2] = 2.946 * ang_vel[1]
    action[3] = -2.601 * ang_vel[2]
    action[4] = -13.83 * ang_vel[1]
    return action
