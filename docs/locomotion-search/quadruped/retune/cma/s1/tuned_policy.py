# tuned by colmo-optimize (gfo=cma): training score 177.30, held-out 165.85
import numpy as np

def policy(obs):
    action = np.array([-0.4551, -0.2138, 2.071, 0.9409, -1.901, -2.25, -1.901, 3.348, 1.178, 1.767, 13.12, 0.4276]) * np.sign(obs[5])
    return action + np.array([0.07558, 0.0383, 0.1318 - 60.46 * np.arctan2(obs[7], obs[1]), 0.1257, -2.281, 0.05505, 1.083, -2.402, -0.68, 0.1767, -0.3439, -0.1155]) * np.tanh(obs[77]) + np.array([0.1523, 0.07666, 0.1313, -0.07987, -0.08685, 2.158, 1.514, -0.2193, -0.2358, -0.0237, -2.047, 0.1024]) * (obs[14] - -0.003686 * obs[20] * obs[74])
