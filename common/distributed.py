"""Which process of a multi-process training run this is, read from what the launcher exported.

`torchrun --nproc_per_node=N train.py ...` exports RANK, WORLD_SIZE and LOCAL_RANK to each of its
N processes; a submitit job with several tasks (Hydra's submitit launcher, `tasks_per_node: 2`)
exports nothing torch reads, so `export_submitit_environment` writes the same variables from
submitit's own job environment (its TorchDistributedEnvironment). Everything here reads the
environment only (no torch), so train.py can ask before torch is imported; models/distributed.py
joins the process group and does the collective work.
"""
import os


def export_submitit_environment() -> None:
    """Inside a submitit job of several tasks, export MASTER_ADDR/PORT, RANK, WORLD_SIZE and
    LOCAL_RANK for torch's env:// rendezvous (once; a process torchrun started already has them).
    CUDA_VISIBLE_DEVICES is left alone: each rank picks cuda:<LOCAL_RANK> itself."""
    if "RANK" in os.environ or "SUBMITIT_EXECUTOR" not in os.environ:
        return
    from submitit import JobEnvironment
    from submitit.helpers import TorchDistributedEnvironment
    if JobEnvironment().num_tasks > 1:
        TorchDistributedEnvironment().export(set_cuda_visible_devices=False)


def launched_world_size() -> int:
    """How many processes the launcher started for this training run (1 without a launcher)."""
    return int(os.environ.get("WORLD_SIZE", "1"))


def launched_rank() -> int:
    """This process's place among them: 0 writes the run folder, the others only train."""
    return int(os.environ.get("RANK", "0"))


def launched_local_rank() -> int:
    """This process's place on its own node (which GPU it drives)."""
    return int(os.environ.get("LOCAL_RANK", "0"))
