# colmo best policy for pendulum: training score 502.20, held-out 527.60 after 200 samples
from math import pi
from numpy import pi, sqrt

def policy(obs):
    omega = obs[2]
    angle = obs[0]
    if abs(angle) < pi / 46.54:
        action = -0.0401
    elif angle > pi / 3.497 - 0.1106:
        action = -omega
    else:
        action = omega
    return action