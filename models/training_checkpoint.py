"""The resumable training checkpoint of models/timeseries_classifier.py: what it holds (the
epoch loop's state, `TrainingState`), how it is written, and how a resume reads and checks it.

A checkpoint holds tensors and plain values only (numbers, strings, lists, tuples, dicts), so a
resume reads it with torch.load(weights_only=True): a file that would run code is refused unread.
"""
import os
from dataclasses import dataclass, field
from pathlib import Path

import torch

from common.errors import InputError

# What a checkpoint must agree on with the fit that resumes it (max_epochs may grow: a run can
# be extended; device and progress do not change the result).
RESUME_KEYS = ("optimizer", "lr", "momentum", "weight_decay", "lr_schedule", "milestones", "gamma", "lr_factor",
               "lr_plateau_patience", "min_lr", "early_stopping_patience", "early_stopping_min_patience",
               "early_stopping_min_delta", "batch_size", "max_batch_fraction", "recalibrate_batchnorm", "seed")
CHECKPOINT_KEYS = ("fingerprint", "epoch", "stopped", "elapsed_s", "module", "optimiser", "schedule", "best",
                   "best_state", "improved", "history", "generator", "torch_rng", "cuda_rng")


@dataclass
class TrainingState:
    """What the epoch loop carries from one epoch to the next; all of it goes into a checkpoint,
    so a resumed fit continues where the interrupted one stood."""
    module: torch.nn.Module
    optimiser: torch.optim.Optimizer
    schedule: object                  # a torch learning-rate scheduler (MultiStepLR, ReduceLROnPlateau)
    generator: torch.Generator        # draws the batch order
    fingerprint: dict                 # the configuration training (checked on resume)
    history: list = field(default_factory=list)   # one record per epoch
    best: tuple | None = None         # the kept epoch's score
    best_state: dict | None = None    # and its weights
    improved: tuple | None = None     # (score..., epoch) of the last improvement that mattered
    epoch: int = 0                    # epochs done
    elapsed_s: float = 0.0            # training time up to the end of that epoch
    stopped: bool = False             # early stopping has ended training

    def checkpoint(self, rank_rngs: list) -> dict:
        """The checkpoint's contents (CHECKPOINT_KEYS); `rank_rngs`: every rank's torch RNG
        state, in rank order (kept per rank when several processes train: dropout draws per rank)."""
        return {"fingerprint": self.fingerprint, "epoch": self.epoch, "stopped": self.stopped,
                "elapsed_s": self.elapsed_s, "module": self.module.state_dict(),
                "optimiser": self.optimiser.state_dict(), "schedule": self.schedule.state_dict(), "best": self.best,
                "best_state": self.best_state, "improved": self.improved, "history": self.history,
                "generator": self.generator.get_state(), "torch_rng": rank_rngs[0],
                "cuda_rng": torch.cuda.get_rng_state_all() if torch.cuda.is_available() else None,
                **({"rank_rngs": rank_rngs} if len(rank_rngs) > 1 else {})}

    def restore(self, state: dict, rank: int, world_size: int) -> None:
        """Continue from a checkpoint's contents (load_checkpoint's), the RNG states included."""
        self.module.load_state_dict(state["module"])
        self.optimiser.load_state_dict(state["optimiser"])
        self.schedule.load_state_dict(state["schedule"])
        self.history, self.best, self.best_state = state["history"], state["best"], state["best_state"]
        self.improved, self.epoch, self.elapsed_s = state["improved"], state["epoch"], state["elapsed_s"]
        self.stopped = state["stopped"]
        self.generator.set_state(state["generator"])
        torch.set_rng_state(state["rank_rngs"][rank] if world_size > 1 else state["torch_rng"])
        if state.get("cuda_rng") is not None and torch.cuda.is_available():
            torch.cuda.set_rng_state_all(state["cuda_rng"])


def save_checkpoint(path, state: dict) -> None:
    """Written to a temporary file and renamed, so a run killed while saving keeps the previous
    epoch's checkpoint."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    torch.save(state, tmp)
    os.replace(tmp, path)


def load_checkpoint(resume_from, fingerprint: dict) -> dict:
    """The state in `resume_from` (a checkpoint file, or a run folder holding one), checked to be a
    Touchstone checkpoint written by the configuration `fingerprint` describes."""
    path = Path(resume_from)
    if path.is_dir():
        path = path / "checkpoint" / "last.pt" if (path / "checkpoint").is_dir() else path / "last.pt"
    if not path.is_file():
        raise InputError(f"trainer.resume_from: no checkpoint at {path}")
    try:  # weights_only: tensors and plain values only; a pickle that would run code is refused unread
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as error:
        raise InputError(f"trainer.resume_from: {path} is not a readable checkpoint (torch.load with "
                         f"weights_only=True refused it: {type(error).__name__})") from None
    missing = sorted(set(CHECKPOINT_KEYS) - set(state)) if isinstance(state, dict) else ["everything"]
    if missing:
        raise InputError(f"trainer.resume_from: {path} is not a Touchstone checkpoint (no {missing[0]!r})")
    saved = {"world_size": 1, **state["fingerprint"]}  # a checkpoint without the key: one process wrote it
    differs = sorted(k for k in fingerprint if saved.get(k) != fingerprint[k])
    if differs:
        raise InputError(f"trainer.resume_from: the checkpoint {path} was written by another configuration "
                         f"({differs[0]}: {saved.get(differs[0])!r} there, {fingerprint[differs[0]]!r} now)")
    return state
