"""Split settings a regression datamodule can honour: checked before any data is loaded (and by
train.py before start-up), so an impossible value is one line, not a failure deep in a split."""
from data.errors import InputError


def check_split_settings(n_folds, test_fraction, val_fraction, calibration_fraction) -> None:
    if isinstance(n_folds, bool) or not isinstance(n_folds, int) or n_folds < 2:
        raise InputError(f"data.n_folds must be an integer >= 2 (the K of K-fold), got {n_folds!r}")
    fractions = {"test_fraction": test_fraction, "val_fraction": val_fraction,
                 "calibration_fraction": calibration_fraction}
    for name, value in fractions.items():
        number = isinstance(value, (int, float)) and not isinstance(value, bool)
        may_be_zero = name == "calibration_fraction"  # 0: calibrate on the validation split
        if not (number and (value >= 0 if may_be_zero else value > 0) and value < 1):
            raise InputError(f"data.{name} must lie in {'[0' if may_be_zero else '(0'}, 1), got {value!r}")
    if sum(fractions.values()) >= 1:
        raise InputError("data.test_fraction + val_fraction + calibration_fraction must be below 1 "
                         f"(training needs rows), got {sum(fractions.values()):.3g}")
