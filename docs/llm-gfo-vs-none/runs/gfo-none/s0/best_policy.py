# colmo best policy for pendulum: training score 187.40, held-out 174.36 after 200 samples
def policy(obs):
    angle = obs[0]
    angular_velocity = obs[2]
    if abs(angle) < 0.5:
        torque = 1.0
    else:
        torque = 0.5
    if torque > 1.0:
        torque = 1.0
    elif torque < -1.0:
        torque = -1.0
    if angular_velocity > 0.5:
        torque = 1.0
    elif angular_velocity < -0.5:
        torque = -1.0
    return torque