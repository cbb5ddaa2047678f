# tuned by colmo-optimize (gfo=oneplusone): training score 262.63, held-out 229.55
import numpy as np

def policy(obs):
    pos = obs[:3]
    vel = obs[3:6]
    ang_vel = obs[6:9]
    action = np.zeros(6)
    action[0] = -17.3 * vel[0]
    action[1] = -0.5211 * ang_vel[0]
    action[2] = 3.322 * ang_vel[1]
    action[3] = -9.31 * ang_vel[2]
    action[4] = -20.15 * ang_vel[1]
    return action
