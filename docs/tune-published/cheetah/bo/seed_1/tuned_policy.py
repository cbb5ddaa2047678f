# tuned by colmo-optimize (gfo=bo): training score 265.06, held-out 240.60
import numpy as np

def policy(obs):
    pos = obs[:3]
    vel = obs[3:6]
    ang_vel = obs[6:9]
    action = np.zeros(6)
    action[0] = -11.96 * vel[0]
    action[1] = -0.3496 * ang_vel[0]
    action[2] = 3.006 * ang_vel[1]
    action[3] = -4.285 * ang_vel[2]
    action[4] = -12.03 * ang_vel[1]
    return action
