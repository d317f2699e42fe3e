"""Several trained networks as one: the log of their mean class probabilities.

InceptionTime's paper (Ismail Fawaz et al. 2020) averages the softmax outputs of five networks
trained from different random initialisations. Returning log(mean p) keeps the contract of a
single network (logits: softmax of the output is the ensemble's probabilities), so training
reports, the deployed pipeline and its one ONNX graph (LogSoftmax, Concat, ReduceLogSumExp) need
nothing of their own.
"""
import math

import torch
from torch import nn

from models.storable import storable


@storable
class MemberAverage(nn.Module):
    def __init__(self, members):
        super().__init__()
        self.members = nn.ModuleList(members)

    def forward(self, x):
        log_p = torch.stack([torch.log_softmax(member(x), dim=1) for member in self.members])
        return torch.logsumexp(log_p, dim=0) - math.log(len(self.members))
