"""Two classifiers scored on the same rows, paired: McNemar's test and the accuracy difference
with its interval, the one statistic the default model's choice (models/validation_choice.py)
uses to say whether one candidate is significantly more accurate than another, and what a
choice gave up.

Only the rows where exactly one of the two is right carry information: `gains` (the first right,
the second wrong) against `losses`. McNemar's z = (gains - losses) / sqrt(gains + losses) (no
continuity correction: the rule the choice has always used). The difference in accuracy is
(gains - losses) / n, and its 95 % interval the paired normal one: its variance is
(gains + losses - (gains - losses)^2 / n) / n^2 (Agresti, Categorical Data Analysis, 10.1).
"""
import math

import numpy as np

Z_95 = 1.959963984540054


def discordant(right_a: np.ndarray, right_b: np.ndarray) -> tuple[int, int]:
    """(rows only a gets right, rows only b gets right)."""
    right_a, right_b = np.asarray(right_a, bool), np.asarray(right_b, bool)
    return int(np.sum(right_a & ~right_b)), int(np.sum(~right_a & right_b))


def mcnemar_z(gains: int, losses: int) -> float:
    """z of `gains` against `losses`; 0 when no row tells them apart."""
    return 0.0 if gains + losses == 0 else (gains - losses) / math.sqrt(gains + losses)


def significantly_better(right_a, right_b, z: float) -> bool:
    """a is right on significantly more rows than b (McNemar z above `z`)."""
    gains, losses = discordant(right_a, right_b)
    return gains > losses and mcnemar_z(gains, losses) > z


def best_reachable_z(errors: int) -> float:
    """The largest z any classifier can reach against one that is wrong on `errors` rows: right
    on all of them and wrong on none of the others."""
    return math.sqrt(errors)


def accuracy_difference(right_a, right_b) -> dict:
    """a's accuracy minus b's on the same rows, with its paired 95 % interval and McNemar's z."""
    gains, losses = discordant(right_a, right_b)
    n = len(np.asarray(right_a))
    difference = (gains - losses) / n
    half = Z_95 * math.sqrt(max(gains + losses - (gains - losses) ** 2 / n, 0.0)) / n
    return {"difference": difference, "interval95": [difference - half, difference + half],
            "gains": gains, "losses": losses, "z": mcnemar_z(gains, losses), "n": n}
