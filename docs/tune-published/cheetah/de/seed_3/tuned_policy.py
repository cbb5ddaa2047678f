# tuned by colmo-optimize (gfo=de): training score 220.43, held-out 219.55
import numpy as np

def policy(obs):
    pos = obs[:3]
    vel = obs[3:6]
    ang_vel = obs[6:9]
    action = np.zeros(6)
    action[0] = -14.53 * vel[0]
    action[1] = -0.648 * ang_vel[0]
    action[2] = 5.747 * ang_vel[1]
    action[3] = -14.62 * ang_vel[2]
    action[4] = -34.51 * ang_vel[1]
    return action
