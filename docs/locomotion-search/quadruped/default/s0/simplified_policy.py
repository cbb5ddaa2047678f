# colmo: the best policy of quadruped simplified: training score 105.77, held-out 105.77
import numpy as np

def policy(obs):
    return np.array([-138.9, -24.86, 15.74, -np.arctan2(obs[76], obs[66]), 16.05, 0.2975, 22.33, -112.0, 0.4423, -16.2, -137.7, -2.321]) * obs[15] * obs[14]
