"""Held-out test, validation and K-fold indices, random or grouped by press point.

`random` is the seed paper's split. `grouped` keeps every repeat of one position-depth pair
on one side, because random splits over repeated presses let a model recognise a repeat
instead of generalising, which overstates accuracy.
"""
import numpy as np
from sklearn.model_selection import GroupKFold, GroupShuffleSplit, KFold, ShuffleSplit

from data.errors import InputError

SPLITS = ("random", "grouped")


def holdout(indices: np.ndarray, groups: np.ndarray, fraction: float, split: str, seed: int):
    """Split `indices` into (kept, held_out) with about `fraction` held out."""
    if split not in SPLITS:
        raise InputError(f"data.split must be one of {', '.join(SPLITS)}, got '{split}'")
    if not 0.0 < fraction < 1.0:
        raise InputError(f"split fractions must lie in (0, 1), got {fraction}")
    if split == "grouped" and np.unique(groups[indices]).size < 2:
        raise InputError("data.split=grouped needs at least two distinct press points")
    if split == "grouped":
        splitter = GroupShuffleSplit(n_splits=1, test_size=fraction, random_state=seed)
        kept, held = next(splitter.split(indices, groups=groups[indices]))
    else:
        kept, held = next(ShuffleSplit(n_splits=1, test_size=fraction, random_state=seed).split(indices))
    return indices[kept], indices[held]


def fold_indices(indices: np.ndarray, groups: np.ndarray, n_folds: int, split: str, seed: int):
    """K folds over `indices`: a list of (fit_indices, fold_indices) pairs, positions into the data."""
    if n_folds < 2:
        raise InputError(f"data.n_folds must be >= 2, got {n_folds}")
    if split == "grouped":
        if np.unique(groups[indices]).size < n_folds:
            raise InputError(f"data.n_folds={n_folds} exceeds the number of press points")
        folds = GroupKFold(n_splits=n_folds, shuffle=True, random_state=seed).split(indices, groups=groups[indices])
    else:
        if indices.size < n_folds:
            raise InputError(f"data.n_folds={n_folds} exceeds the {indices.size} training rows")
        folds = KFold(n_splits=n_folds, shuffle=True, random_state=seed).split(indices)
    return [(indices[a], indices[b]) for a, b in folds]
