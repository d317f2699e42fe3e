"""Exact training-set BatchNorm statistics for a network's current weights.

The stored (eval-mode) statistics are a running average over the last few training batches,
which with few optimiser steps have not settled (a model scored 0.85 on its own training windows
in eval mode and 1.00 with batch statistics). Recomputed over all training windows before each
validation pass (as torch.optim.swa_utils.update_bn does after weight averaging), the scored and
the deployed model are the same network, and the training trajectory is unchanged (training
batches normalise with their own statistics).
"""
import torch
from torch import nn

from models.distributed import TrainingGroup


def recalibrate_batchnorm(module: nn.Module, batches, device, group: TrainingGroup) -> None:
    """Momentum None: a cumulative average over `batches` (the training windows). Only the
    BatchNorm layers are put in training mode, so dropout draws no random numbers and the RNG
    stream is left as it was. With several ranks each computes its shard of every batch and the
    moments are summed. Leaves the module in eval mode."""
    norms = [m for m in module.modules() if isinstance(m, nn.modules.batchnorm._BatchNorm)]
    if not norms:
        return
    momenta = [m.momentum for m in norms]
    module.eval()
    for m in norms:
        m.reset_running_stats()
        m.momentum = None
        m.train()
    with torch.no_grad():
        for batch in batches:
            module(group.shard(batch).to(device))
    for m, momentum in zip(norms, momenta):
        m.momentum = momentum
    module.eval()
