# colmo: the best policy of cheetah simplified: training score 301.45, held-out 310.61
import numpy as np

def policy(obs):
    return np.array([-21.28, -1.558, -5.349, 0.4344, 13.56, 1.517]) * obs[3]
