"""One net trained by several processes (torchrun, or submitit tasks) to the result of one process.

The nets' estimators (models/timeseries_classifier.py, models/resmlp_regressor.py) train through a
`TrainingGroup`: with one process it changes nothing; with N it is DistributedDataParallel over
torch.distributed (gloo on CPU, NCCL for CUDA tensors, one process group for both) with these rules,
chosen so that N processes compute what one process computes with the same global batch and seed:

- Every rank draws the same epoch order from the run's seed, cuts it into the same global batches,
  and takes every N-th window of each (`shard`: the distributed sampler). torch's DistributedSampler
  pads or drops windows to give every rank as many, which one process never does.
- Each rank's loss is its shard's mean loss weighted by its share of the global batch times N, so
  DDP's average of the ranks' gradients is the gradient of the global batch's mean loss, also when
  the last batch does not divide evenly. A global batch with fewer windows than ranks is skipped
  (one process skips only batches of one window, which BatchNorm cannot normalise).
- BatchNorm normalises with the global batch's moments: `SynchronisedBatchNorm` all-reduces the sum
  and the centred sum of squares (differentiably, so gradients flow through the global moments as
  they do in one process). torch's SyncBatchNorm does the same but only for CUDA tensors.
- Dropout and input noise draw from a stream seeded by the run's seed and the rank (`rank_seed`):
  rank 0 keeps the run's seed, so one process trains exactly as before; a net with dropout then
  differs from one process by its masks, i.e. by seed noise.
- Validation runs on every rank (same weights, same windows) and rank 0's result is the one every
  rank acts on (`agree`), so the learning-rate schedule and early stopping never diverge.
"""
import atexit
import os
import tempfile
import time
from pathlib import Path

import numpy as np
import torch
import torch.distributed as dist
import torch.multiprocessing as multiprocessing
from sklearn.base import clone
from torch import nn
from torch.nn.parallel import DistributedDataParallel

from common.distributed import export_submitit_environment, launched_local_rank, launched_world_size
from models.fitted_state import load_fitted, save_fitted


def join_process_group() -> bool:
    """Join the training run's process group when a launcher started several processes (once per
    process; the env:// rendezvous torchrun or `export_submitit_environment` set up). Returns
    whether this process is one of several."""
    export_submitit_environment()
    if launched_world_size() < 2:
        return False
    if not dist.is_initialized():
        dist.init_process_group("cpu:gloo,cuda:nccl" if torch.cuda.is_available() else "gloo")
        atexit.register(_leave_process_group)  # left alive at exit, gloo's threads abort the process
    return True


def _leave_process_group() -> None:
    if dist.is_initialized():
        dist.destroy_process_group()


def rank_seed(seed: int, rank: int) -> int:
    """The seed of rank `rank`'s dropout and noise: the run's seed on rank 0, an independent
    stream (numpy's SeedSequence of the pair) on the others."""
    if rank == 0:
        return int(seed)
    return int(np.random.SeedSequence([int(seed) % 2 ** 64, rank]).generate_state(1, np.uint64)[0] % 2 ** 63)


class _SumOverRanks(torch.autograd.Function):
    """A tensor summed over the ranks, differentiable: every rank's loss depends on every rank's
    contribution, so the gradient that flows back is the sum of the ranks' gradients."""

    @staticmethod
    def forward(ctx, tensor):
        total = tensor.clone()
        dist.all_reduce(total)
        return total

    @staticmethod
    def backward(ctx, grad):
        total = grad.clone()
        dist.all_reduce(total)
        return total


def summed_over_ranks(tensor: torch.Tensor) -> torch.Tensor:
    return _SumOverRanks.apply(tensor)


class SynchronisedBatchNorm(nn.BatchNorm1d):
    """BatchNorm1d whose training-mode statistics are the moments of the global batch, summed over
    all ranks (any backend: gloo too); evaluation mode and a lone process behave as BatchNorm1d.
    Running statistics are updated as BatchNorm1d updates them, with the global count."""

    def forward(self, x):
        if not (self.training and dist.is_initialized() and dist.get_world_size() > 1):
            return super().forward(x)
        dims = [0] + list(range(2, x.dim()))
        shape = [1, -1] + [1] * (x.dim() - 2)
        local_count = torch.full((1,), x.numel() / max(x.shape[1], 1), dtype=x.dtype, device=x.device)
        totals = summed_over_ranks(torch.cat([x.sum(dims), local_count]))
        count = totals[-1]
        mean = totals[:-1] / count
        centred = x - mean.view(shape)
        var = summed_over_ranks((centred * centred).sum(dims)) / count
        if self.track_running_stats:
            with torch.no_grad():
                self.num_batches_tracked += 1
                factor = 1.0 / float(self.num_batches_tracked) if self.momentum is None else self.momentum
                self.running_mean.mul_(1 - factor).add_(factor * mean.detach())
                unbiased = var.detach() * (count / torch.clamp(count - 1, min=1))
                self.running_var.mul_(1 - factor).add_(factor * unbiased)
        out = centred * torch.rsqrt(var + self.eps).view(shape)
        if self.affine:
            out = out * self.weight.view(shape) + self.bias.view(shape)
        return out


def _swap_batchnorm(module: nn.Module, to: type) -> None:
    """Turn every BatchNorm1d below `module` into class `to` in place: SynchronisedBatchNorm adds
    no state, so the same parameters and buffers stay (the optimiser, state_dict keys, checkpoints
    and the ONNX export see no difference)."""
    for child in module.modules():
        if isinstance(child, nn.BatchNorm1d):
            child.__class__ = to


class TrainingGroup:
    """This process's part in training one net: rank and size of the group (0 and 1 alone), the
    shard of a global batch it computes, and the collective steps of an epoch."""

    def __init__(self):
        self.distributed = dist.is_initialized() and dist.get_world_size() > 1
        self.rank = dist.get_rank() if self.distributed else 0
        self.size = dist.get_world_size() if self.distributed else 1

    @property
    def is_writer(self) -> bool:
        """Rank 0 alone writes files (checkpoints, the run folder)."""
        return self.rank == 0

    def smallest_batch(self) -> int:
        """A global batch needs two windows (BatchNorm) and one per rank."""
        return max(2, self.size)

    def shard(self, batch: torch.Tensor) -> torch.Tensor:
        return batch[self.rank::self.size]

    def share(self, shard_size: int, batch_size: int) -> float:
        """Weight of a shard's mean loss: exactly 1.0 for one process."""
        return shard_size * self.size / batch_size

    def device(self, device: torch.device) -> torch.device:
        """Each rank drives the GPU of its local rank."""
        if self.distributed and device.type == "cuda":
            device = torch.device("cuda", launched_local_rank())
            torch.cuda.set_device(device)
        return device

    def prepare(self, module: nn.Module) -> nn.Module:
        """The module to train: itself alone; with several ranks its BatchNorm synchronised and
        the whole wrapped in DistributedDataParallel (which starts every rank from rank 0's
        weights). `release` undoes the BatchNorm swap after training."""
        if not self.distributed:
            return module
        _swap_batchnorm(module, SynchronisedBatchNorm)
        device_ids = [module_device(module)] if module_device(module).type == "cuda" else None
        return DistributedDataParallel(module, device_ids=device_ids, forward_sync_buffers=False)

    def release(self, module: nn.Module) -> None:
        if self.distributed:
            _swap_batchnorm(module, nn.BatchNorm1d)

    def totals(self, values: list[float]) -> list[float]:
        """Each value summed over the ranks (one all-reduce)."""
        if not self.distributed:
            return list(values)
        tensor = torch.tensor(values, dtype=torch.float64)
        dist.all_reduce(tensor)
        return tensor.tolist()

    def agree(self, value):
        """Rank 0's value of any picklable object, on every rank."""
        if not self.distributed:
            return value
        box = [value]
        dist.broadcast_object_list(box, src=0)
        return box[0]

    def gather(self, value) -> list:
        """Every rank's value, in rank order, on every rank."""
        if not self.distributed:
            return [value]
        values = [None] * self.size
        dist.all_gather_object(values, value)
        return values


def module_device(module: nn.Module) -> torch.device:
    return next(module.parameters()).device


def fit_in_processes(estimator, n_processes: int, *fit_args, threads: int = 1, **fit_kwargs):
    """Fit a clone of `estimator` with `n_processes` processes on this machine (gloo, as
    `torchrun --standalone --nproc_per_node=n_processes` would run it; one process: alone, in a
    child all the same) and return rank 0's fitted estimator, with `fit_wall_s_`, the wall time of
    its fit: what the tests and bench/ddp_step_time.py compare with a one-process fit."""
    with tempfile.TemporaryDirectory() as folder:
        # rank 0 hands its fit back in the fitted-state format every run's pipeline.npz uses (no
        # pickle: nothing on disk here can run code when read), after every child has ended
        multiprocessing.start_processes(
            _fit_rank, args=(n_processes, folder, threads, estimator, fit_args, fit_kwargs),
            nprocs=n_processes, start_method="fork", join=True)  # raises when a child failed
        return load_fitted(Path(folder) / "rank0.npz")


def _fit_rank(rank, n_processes, folder, threads, estimator, fit_args, fit_kwargs):
    torch.set_num_threads(threads)
    if n_processes > 1:
        os.environ.update(RANK=str(rank), WORLD_SIZE=str(n_processes), LOCAL_RANK=str(rank))
        dist.init_process_group("gloo", init_method=f"file://{folder}/rendezvous", rank=rank, world_size=n_processes)
    try:
        start = time.perf_counter()
        fitted = clone(estimator).fit(*fit_args, **fit_kwargs)
        fitted.fit_wall_s_ = time.perf_counter() - start
        if rank == 0:
            save_fitted(fitted, Path(folder) / "rank0.npz")
    finally:
        if dist.is_initialized():
            dist.destroy_process_group()
