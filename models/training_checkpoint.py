"""The resumable training checkpoint of models/timeseries_classifier.py: what it holds, how it is
written, and how a resume reads and checks it.

A checkpoint holds tensors and plain values only (numbers, strings, lists, tuples, dicts), so a
resume reads it with torch.load(weights_only=True): a file that would run code is refused unread.
"""
import os
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
