"""Held-out test, validation and K-fold indices, grouped by press point or random.

`grouped` (the default) keeps every repeat of one position-depth pair on one side, because
random splits over repeated presses let a model recognise a repeat instead of generalising,
which overstates accuracy. `random` is the seed paper's protocol (repeats shared).
"""
import numpy as np
from sklearn.model_selection import GroupKFold, GroupShuffleSplit, KFold, ShuffleSplit

from data.errors import InputError

SPLITS = ("random", "grouped")
# What a reader of the figures must know about each split; metrics.json and the README carry it.
SPLIT_NOTES = {"grouped": "every repeat of a position-depth pair on one side (no press shared)",
               "random": "the paper's protocol, repeats shared between training and test"}


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


def kfold_indices(n_rows: int, n_folds: int, seed: int, groups=None):
    """K folds over rows 0..n_rows-1: ([(fit_rows, held_rows), ...], warning or None).

    With `groups`, every group's rows stay in one fold (GroupKFold, shuffled by `seed`). Grouped
    folds never fall back to ungrouped ones: with fewer groups than folds, each group becomes a
    fold and the returned warning says so (callers record it); fewer than two groups is an error.
    """
    if n_folds < 2:
        raise InputError(f"K-fold needs n_folds >= 2, got {n_folds}")
    warning = None
    if groups is not None:
        groups = np.asarray(groups)
        if len(groups) != n_rows:
            raise InputError(f"K-fold: {len(groups)} group ids for {n_rows} rows")
        n_groups = np.unique(groups).size
        if n_groups < 2:
            raise InputError("grouped K-fold needs at least two groups (press points) in the training split")
        if n_groups < n_folds:
            warning = (f"grouped K-fold: only {n_groups} groups in the training split, so {n_groups} folds "
                       f"instead of {n_folds}")
            n_folds = n_groups
        splitter = GroupKFold(n_splits=n_folds, shuffle=True, random_state=seed)
        folds = splitter.split(np.zeros(n_rows), groups=groups)
    else:
        if n_rows < n_folds:
            raise InputError(f"K-fold with n_folds={n_folds} needs at least that many rows, got {n_rows} "
                             f"sample{'' if n_rows == 1 else 's'}")
        folds = KFold(n_splits=n_folds, shuffle=True, random_state=seed).split(np.zeros(n_rows))
    return [(fit, held) for fit, held in folds], warning


def carve_validation(n_rows: int, fraction: float, seed: int, groups=None):
    """(fit_rows, validation_rows) for a model that must early-stop and was given no validation
    split: grouped when `groups` are given (every repeat of a press on one side), else random."""
    rows = np.arange(n_rows)
    if groups is None:
        return holdout(rows, rows, fraction, "random", seed)
    return holdout(rows, np.asarray(groups), fraction, "grouped", seed)
