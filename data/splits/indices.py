"""Held-out test, validation and K-fold indices: grouped by press point, random, or the split a
user's file declares.

`grouped` (the default) keeps every repeat of one position-depth pair on one side, because
random splits over repeated presses let a model recognise a repeat instead of generalising,
which overstates accuracy. `random` is the seed paper's protocol (repeats shared).
`predefined` takes the sides a data set comes with (a `split` column or array, values train /
val / test): published recording sets are compared on their own test split, so a tool that
re-splits them cannot reproduce a published figure. When no validation rows are declared,
validation is carved from the train rows only; the test rows are never used for any choice.
`auto` (the default) is `predefined` when the data declare a split and the drawn default
otherwise (resolve_split): a declared split is ignored only when data.declared_split=ignore says so.
"""
import warnings

import numpy as np
from sklearn.model_selection import (
    GroupKFold,
    GroupShuffleSplit,
    KFold,
    ShuffleSplit,
    StratifiedGroupKFold,
)

from common.errors import InputError

SPLITS = ("random", "grouped")   # what holdout() draws; the regression datamodule also takes auto, predefined
AUTO = "auto"                    # the data's declared split when they declare one, else the datamodule's drawn default
REGRESSION_SPLITS = (AUTO,) + SPLITS + ("predefined",)
PREDEFINED_VALUES = ("train", "val", "test")
DECLARED_SPLIT_CHOICES = ("use", "ignore")   # data.declared_split: what to do with a split the data declare
# What a reader of the figures must know about each split; metrics.json and the README carry it.
SPLIT_NOTES = {"grouped": "every repeat of a position-depth pair on one side (no press shared)",
               "random": "the paper's protocol, repeats shared between training and test",
               "predefined": "the data's own train / val / test labels; without val rows, validation "
                             "is carved from the train rows (by group or recording), test is never chosen on",
               "force_level": "train on the recorded force levels, validation and test on unseen levels, "
                              "divided by recording",
               "stratified": "test, then validation, held out by recording, stratified by label"}


def holdout(indices: np.ndarray, groups: np.ndarray, fraction: float, split: str, seed: int):
    """Split `indices` into (kept, held_out) with about `fraction` held out."""
    if split not in SPLITS:
        raise InputError(f"data.split must be one of {', '.join(REGRESSION_SPLITS)}, got '{split}'")
    if not 0.0 < fraction < 1.0:
        raise InputError(f"split fractions must lie in (0, 1), got {fraction}")
    if split == "grouped" and np.unique(groups[indices]).size < 2:
        raise InputError("data.split=grouped needs at least two distinct press points")
    try:
        if split == "grouped":
            splitter = GroupShuffleSplit(n_splits=1, test_size=fraction, random_state=seed)
            kept, held = next(splitter.split(indices, groups=groups[indices]))
        else:
            kept, held = next(ShuffleSplit(n_splits=1, test_size=fraction, random_state=seed).split(indices))
    except ValueError as error:  # too few rows for the share (a one-row table): scikit-learn says how many
        raise InputError(f"data.split={split}: cannot hold out {fraction:g} of {len(indices)} row(s) "
                         f"({str(error).splitlines()[0]})") from None
    return indices[kept], indices[held]


# -- predefined splits -------------------------------------------------------------------------
def resolve_split(requested: str, declared: bool, declared_split: str, drawn: str, where: str) -> tuple[str, str]:
    """(the split a run uses, one line saying where it comes from).

    A split the data declare is used by default: a user's test recordings must never slip into
    training because a setting was left out. `data.split=auto` (the default) takes it when there
    is one and draws `drawn` otherwise; ignoring a declared split takes `data.declared_split=ignore`;
    asking to draw a split (data.split=grouped, stratified, ...) from data that declare one,
    without saying to ignore it, is an error rather than a guess.
    """
    if declared_split not in DECLARED_SPLIT_CHOICES:
        raise InputError(f"data.declared_split must be one of {', '.join(DECLARED_SPLIT_CHOICES)}, "
                         f"got {declared_split!r}")
    use = declared and declared_split == "use"
    if requested == AUTO:
        requested = "predefined" if use else drawn
    elif use and requested != "predefined":
        raise InputError(f"{where} declares its own train / val / test split, but data.split={requested} asks to "
                         f"draw one; leave data.split at auto to use the declared split, or set "
                         f"data.declared_split=ignore to draw {requested}")
    elif requested == "predefined" and declared_split == "ignore":
        raise InputError("data.split=predefined uses the split the data declare, which data.declared_split=ignore "
                         "ignores; choose one")
    if requested == "predefined":
        return requested, f"the train / val / test split {where} declares (data.declared_split=ignore draws one instead)"
    if declared:
        return requested, f"{requested}, drawn; the split {where} declares is ignored (data.declared_split=ignore)"
    return requested, f"{requested}, drawn ({where} declares no split)"


def split_values(values, where: str, entry=lambda k: f"entry {k}") -> np.ndarray:
    """Declared split labels as 'train' / 'val' / 'test' (case and surrounding spaces ignored);
    anything else (a typo, 'validation', an empty or missing cell) is one line naming it and
    `entry(k)`, where a user finds it (an array index, a file line)."""
    def clean(value) -> str:
        if isinstance(value, bytes):
            value = value.decode(errors="replace")
        return value.strip().lower() if isinstance(value, str) else ""
    raw = np.asarray(values, dtype=object).reshape(-1)
    cleaned = np.array([clean(v) for v in raw], dtype=object)
    unknown = ~np.isin(cleaned, PREDEFINED_VALUES)
    if unknown.any():
        k = int(np.flatnonzero(unknown)[0])
        value = raw[k].item() if isinstance(raw[k], np.generic) else raw[k]
        raise InputError(f"{where}: split value {value!r} in {entry(k)} is not one of "
                         f"{', '.join(PREDEFINED_VALUES)}")
    return cleaned.astype(str)


def check_one_value_per_group(values, groups, where: str, what: str = "group", value: str = "split value") -> None:
    """Every group (recording, press point) carries one value (its split side, its label): rows of
    one recording on two sides would let the model see part of what it is tested on, and a label
    that changes inside a recording is not the label of one sample."""
    values, groups = np.asarray(values), np.asarray(groups)
    order = np.argsort(groups, kind="stable")
    groups_sorted, values_sorted = groups[order], values[order]
    differs = (groups_sorted[1:] == groups_sorted[:-1]) & (values_sorted[1:] != values_sorted[:-1])
    if differs.any():
        name = groups_sorted[int(np.flatnonzero(differs)[0])]
        sides = sorted(set(values[groups == name].tolist()), key=str)
        name = name.item() if isinstance(name, np.generic) else name
        raise InputError(f"{where}: {what} {name!r} has rows labelled {' and '.join(map(str, sides))}; "
                         f"all rows of one {what} must carry one {value}")


def _carve(train: np.ndarray, fraction: float, seed: int, groups, strata, where: str):
    """(fit, validation) from the train rows only: grouped when groups are given, stratified when
    strata (class labels) are given, both when both are."""
    if not (isinstance(fraction, (int, float)) and not isinstance(fraction, bool) and 0.0 < fraction < 1.0):
        raise InputError(f"data.val_fraction must lie in (0, 1) to carve validation from the train rows, "
                         f"got {fraction!r}")
    row_groups = np.asarray(groups)[train] if groups is not None else None
    row_strata = np.asarray(strata).astype(str)[train] if strata is not None else None
    n_units = np.unique(row_groups).size if row_groups is not None else len(train)
    if n_units < 2:
        raise InputError(f"data.split=predefined: {where} has {n_units} train "
                         f"{'group' if groups is not None else 'row'}; validation needs another one "
                         "(declare 'val' rows or add train rows)")
    dummy = np.zeros(len(train))
    try:
        if row_strata is not None and row_groups is not None:
            n_splits = min(max(2, round(1.0 / fraction)), n_units)
            fit, val = next(StratifiedGroupKFold(n_splits=n_splits, shuffle=True, random_state=seed)
                            .split(dummy, row_strata, row_groups))
        elif row_strata is not None:
            fit, val = _carve_per_class(row_strata, fraction, seed)
        elif row_groups is not None:
            fit, val = next(GroupShuffleSplit(n_splits=1, test_size=fraction, random_state=seed)
                            .split(dummy, groups=row_groups))
        else:
            fit, val = next(ShuffleSplit(n_splits=1, test_size=fraction, random_state=seed).split(dummy))
    except ValueError as error:  # too few rows per class for the share: say so, never fall back
        raise InputError(f"data.split=predefined: cannot carve validation from the train rows of {where} "
                         f"({str(error).splitlines()[0]}); declare 'val' rows") from None
    if len(fit) == 0 or (len(val) == 0 and row_strata is None):
        raise InputError(f"data.split=predefined: data.val_fraction={fraction} leaves training or validation "
                         f"without rows of {where}; declare 'val' rows")
    return np.sort(train[fit]), np.sort(train[val])


def _carve_per_class(strata: np.ndarray, fraction: float, seed: int):
    """(fit, validation) positions: ceil(`fraction` x rows) to validation, shared among the
    classes in proportion to their size (the remainder to the largest fractional shares, ties
    drawn), as a stratified shuffle split does, but never a class's last row: every class keeps
    a training row, so a set with one or two recordings per class still trains (a class of one
    gives validation none; a net then chooses its epochs on folds of the training recordings,
    models/timeseries_classifier.py)."""
    rng = np.random.default_rng(seed)
    labels, counts = np.unique(strata, return_counts=True)
    room = counts - 1
    exact = fraction * counts
    quota = np.minimum(np.floor(exact).astype(int), room)
    remainder = int(np.ceil(fraction * len(strata))) - quota.sum()
    for k in sorted(range(len(labels)), key=lambda k: (quota[k] - exact[k], rng.random())):
        if remainder <= 0:
            break
        if quota[k] < room[k]:
            quota[k] += 1
            remainder -= 1
    held = np.concatenate([rng.permutation(np.flatnonzero(strata == label))[:q] for label, q in zip(labels, quota)])
    held = np.sort(held.astype(np.int64))
    return np.setdiff1d(np.arange(len(strata)), held), held


def stratified_folds(labels, groups, n_folds: int, seed: int):
    """[(fit_rows, held_rows), ...]: about `n_folds` folds by group (every row of a recording in
    one fold), stratified by label. Fewer folds when there are fewer groups; a class with fewer
    groups than folds is in some folds only, so a set with one recording per class still gets
    folds (each held-out recording of such a class is one the fit never saw)."""
    labels, groups = np.asarray(labels).astype(str), np.asarray(groups)
    n_groups = np.unique(groups).size
    if n_groups < 2:
        raise InputError(f"validation folds need at least two training recordings, got {n_groups}")
    n_folds, dummy = min(int(n_folds), n_groups), np.zeros(len(labels))
    with warnings.catch_warnings():  # "the least populated class has only k members": intended here
        warnings.simplefilter("ignore", UserWarning)
        try:
            folds = list(StratifiedGroupKFold(n_splits=n_folds, shuffle=True, random_state=seed)
                         .split(dummy, labels, groups))
        except ValueError:  # every class has fewer recordings than folds: nothing to stratify
            folds = list(GroupKFold(n_splits=n_folds, shuffle=True, random_state=seed).split(dummy, groups=groups))
    return [(fit, held) for fit, held in folds if len(fit) and len(held)]


def predefined_split(values, val_fraction: float, seed: int, where: str, groups=None, strata=None):
    """(train, validation, test) row indices from the split labels a data set declares.

    `values` one label per row (train / val / test); `groups` keep rows of one group (recording,
    press point) on one side; `strata` (class labels) stratify a carved validation split. Without
    val rows, validation is carved from the train rows (`val_fraction` of them); test rows are
    only ever returned as test.
    """
    if values is None:
        raise InputError(f"data.split=predefined needs a split per row: an array 'split' in an NPZ or a "
                         f"'split' column in a table (train / val / test); {where} has none")
    values = split_values(values, where)
    if groups is not None:
        check_one_value_per_group(values, groups, where)
    train, val, test = (np.flatnonzero(values == side) for side in PREDEFINED_VALUES)
    if test.size == 0:
        raise InputError(f"data.split=predefined: {where} has no test rows (split values found: "
                         f"{', '.join(sorted(set(values.tolist())))})")
    if train.size == 0:
        raise InputError(f"data.split=predefined: {where} has no train rows (split values found: "
                         f"{', '.join(sorted(set(values.tolist())))})")
    if val.size == 0:
        train, val = _carve(train, val_fraction, seed, groups, strata, where)
    return train, val, test


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
