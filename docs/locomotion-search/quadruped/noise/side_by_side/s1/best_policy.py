# colmo best policy for quadruped: training score 121.12, held-out 124.43 after 16 samples
import numpy as np

def policy(obs):
    action = np.zeros(12) + np.array([-0.9521, 0.423, -0.289, 1.559, -0.9995, 0.3214, -1.711, 0.7885, 0.5947, 0.7936, 3.343, 0.05133]) * np.sign(obs[5])
    return action + np.array([0.1895, 0.9317, -1.393 - -15.82 * np.arctan2(obs[7], obs[1]), -0.3804, -0.733, 0.1213, 4.53, -2.407, -1.351, 0.428, -0.2927, -0.5619]) * np.tanh(obs[77])