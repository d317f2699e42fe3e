"""Split settings a regression datamodule can honour: checked before any data is loaded (and by
train.py before start-up), so an impossible value is one line, not a failure deep in a split."""
from common.errors import InputError
from data.splits.indices import REGRESSION_SPLITS


def check_split_settings(n_folds, test_fraction, val_fraction, calibration_fraction, split=None) -> None:
    """`split=None` checks the fractions alone (as before the split was known here)."""
    if split is not None and split not in REGRESSION_SPLITS:
        raise InputError(f"data.split must be one of {', '.join(REGRESSION_SPLITS)}, got {split!r}")
    if isinstance(n_folds, bool) or not isinstance(n_folds, int) or n_folds < 2:
        raise InputError(f"data.n_folds must be an integer >= 2 (the K of K-fold), got {n_folds!r}")
    fractions = {"test_fraction": test_fraction, "val_fraction": val_fraction,
                 "calibration_fraction": calibration_fraction}
    for name, value in fractions.items():
        number = isinstance(value, (int, float)) and not isinstance(value, bool)
        may_be_zero = name == "calibration_fraction"  # 0: calibrate on the validation split
        if not (number and (value >= 0 if may_be_zero else value > 0) and value < 1):
            raise InputError(f"data.{name} must lie in {'[0' if may_be_zero else '(0'}, 1), got {value!r}")
    if split == "predefined":
        # The file says which rows are test: validation (when not declared) and calibration are
        # shares of its train rows, and test_fraction is not used.
        if val_fraction + calibration_fraction >= 1:
            raise InputError("data.split=predefined: data.val_fraction + calibration_fraction are shares of the "
                             f"train rows and must be below 1, got {val_fraction + calibration_fraction:.3g}")
        return
    if sum(fractions.values()) >= 1:
        raise InputError("data.test_fraction + val_fraction + calibration_fraction must be below 1 "
                         f"(training needs rows), got {sum(fractions.values()):.3g}")
