# tuned by colmo-optimize (gfo=bo): training score 228.05, held-out 230.59
import numpy as np

def policy(obs):
    pos = obs[:3]
    vel = obs[3:6]
    ang_vel = obs[6:9]
    action = np.zeros(6)
    action[0] = -12.5 * vel[0]
    action[1] = -0.2949 * ang_vel[0]
    action[2] = 3.729 * ang_vel[1]
    action[3] = -2.056 * ang_vel[2]
    action[4] = -23.3 * ang_vel[1]
    return action
