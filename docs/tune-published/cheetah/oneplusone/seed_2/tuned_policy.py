# tuned by colmo-optimize (gfo=oneplusone): training score 197.58, held-out 217.80
import numpy as np

def policy(obs):
    pos = obs[:3]
    vel = obs[3:6]
    ang_vel = obs[6:9]
    action = np.zeros(6)
    action[0] = -18.85 * vel[0]
    action[1] = -0.3333 * ang_vel[0]
    action[2] = 4.321 * ang_vel[1]
    action[3] = -14.56 * ang_vel[2]
    action[4] = -17.55 * ang_vel[1]
    return action
