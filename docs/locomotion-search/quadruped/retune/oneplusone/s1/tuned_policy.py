# tuned by colmo-optimize (gfo=oneplusone): training score 174.47, held-out 159.84
import numpy as np

def policy(obs):
    action = np.array([-0.3235, -0.1996, 1.574, 0.869, -2.147, -2.059, -1.716, 3.196, 1.197, 1.361, 10.93, 0.7058]) * np.sign(obs[5])
    return action + np.array([0.0957, 0.02532, 0.2157 - 59.13 * np.arctan2(obs[7], obs[1]), 0.1029, -2.056, 0.0758, 0.951, -2.01, -0.6314, 0.29, -0.263, -0.1092]) * np.tanh(obs[77]) + np.array([0.184, 0.07589, 0.1529, -0.05442, -0.07759, 1.54, 1.924, -0.2383, -0.1991, -0.03276, -1.535, 0.0951]) * (obs[14] - -0.01594 * obs[20] * obs[74])
