"""Scores: regression per target in physical units (averaged over targets only where the score
is unitless: R^2 and MAPE; an average of RMSE would add millimetres to pascals), classification
as accuracy, macro-F1, log loss, per-class and per-force-level accuracy.

Regression:

R^2 = 1 - SS_res / SS_tot, as scikit-learn: a constant target (SS_tot = 0) scores 1.0 if
predicted exactly, else 0.0. Where SS_tot is so small that the ratio overflows (targets spread
over 1e-157, say) R^2 is floored at -1e12 instead of -inf. It is undefined for a single sample
and reported as None (null in metrics.json); the average skips it.
MAPE is in percent over the rows whose true value is not zero: a target within rounding of
zero (|y| <= 1e-6 of the target's largest magnitude) has no percentage error, and dividing by it
printed 8.67e+06 % for a force that is sometimes 0 N. Where such rows exist, `mape_notes` says
for which targets and how many rows MAPE leaves out (metrics.json `metric_notes`, a log warning);
a target that is zero on every row has no MAPE (None).
"""
import numpy as np
from sklearn.metrics import (confusion_matrix, f1_score, log_loss, mean_absolute_error,
                             mean_absolute_percentage_error, mean_squared_error)

METRICS = ("r2", "rmse", "mae", "mape_pct")
UNITLESS = ("r2", "mape_pct")   # the only scores that may be averaged over targets


R2_FLOOR = -1e12


def r_squared(true: np.ndarray, pred: np.ndarray) -> float | None:
    if len(true) < 2:
        return None
    ss_res = float(np.sum((true - pred) ** 2))
    ss_tot = float(np.sum((true - true.mean()) ** 2))
    if ss_tot == 0.0:
        return 1.0 if ss_res == 0.0 else 0.0
    with np.errstate(over="ignore", divide="ignore"):
        ratio = ss_res / ss_tot
    return float(max(1.0 - ratio, R2_FLOOR)) if np.isfinite(ratio) else R2_FLOOR


ZERO_RELATIVE = 1e-6   # |y| at or below this share of the target's largest magnitude counts as zero


def nonzero_rows(true: np.ndarray) -> np.ndarray:
    """The rows a percentage error is defined on: true value not within rounding of zero."""
    magnitude = np.abs(true)
    return magnitude > ZERO_RELATIVE * float(np.max(magnitude, initial=0.0))


def _scores(true: np.ndarray, pred: np.ndarray) -> dict:
    kept = nonzero_rows(true)
    return {
        "r2": r_squared(true, pred),
        "rmse": float(np.sqrt(mean_squared_error(true, pred))),
        "mae": float(mean_absolute_error(true, pred)),
        # scikit-learn's MAPE floors each |y| at machine epsilon, so a kept denormal stays finite
        "mape_pct": float(100.0 * mean_absolute_percentage_error(true[kept], pred[kept])) if kept.any() else None,
    }


def mape_notes(parts: dict, target_names: list[str]) -> list[str]:
    """One line per split and target whose MAPE leaves rows out: {split: y_true} -> notes."""
    notes = []
    for split, y_true in parts.items():
        y_true = np.asarray(y_true, dtype=np.float64).reshape(len(y_true), -1)
        for k, name in enumerate(target_names):
            zero = int((~nonzero_rows(y_true[:, k])).sum())
            if zero:
                notes.append(f"{split} {name}: {zero} of {len(y_true)} true values are zero; MAPE is over the other "
                             f"{len(y_true) - zero} (a percentage of zero is not defined)")
    return notes


def regression_metrics(y_true, y_pred, target_names: list[str]) -> dict:
    """{target: {r2, rmse, mae, mape_pct}, ..., "average": {r2, mape_pct} uniform means over targets}."""
    y_true = np.asarray(y_true, dtype=np.float64).reshape(len(y_true), -1)
    y_pred = np.asarray(y_pred, dtype=np.float64).reshape(y_true.shape)
    scores = {name: _scores(y_true[:, k], y_pred[:, k]) for k, name in enumerate(target_names)}
    def mean(values):
        values = [v for v in values if v is not None]
        return float(np.mean(values)) if values else None

    scores["average"] = {m: mean([scores[t][m] for t in target_names]) for m in UNITLESS}
    return scores


def format_table(metrics: dict, splits=("val", "test")) -> str:
    """A plain-text table: one row per split and target, one column per metric."""
    lines = [f"{'split':<6}{'target':<14}" + "".join(f"{m:>12}" for m in METRICS)]
    for split in splits:
        for target, row in metrics[split].items():
            lines.append(f"{split:<6}{target:<14}" + "".join(
                f"{row[m]:>12.4g}" if row.get(m) is not None else f"{'—':>12}" for m in METRICS))
    return "\n".join(lines)


def classification_metrics(y_true, proba, classes, levels=None) -> dict:
    predicted = proba.argmax(axis=1)
    labels = np.arange(len(classes))
    matrix = confusion_matrix(y_true, predicted, labels=labels)
    per_class = np.divide(matrix.diagonal(), matrix.sum(axis=1), out=np.full(len(classes), np.nan),
                          where=matrix.sum(axis=1) > 0)
    result = {"accuracy": float((predicted == y_true).mean()),
              "macro_f1": float(f1_score(y_true, predicted, labels=labels, average="macro", zero_division=0)),
              "loss": float(log_loss(y_true, np.clip(proba, 1e-12, 1), labels=labels)),
              "per_class_accuracy": {c: float(a) for c, a in zip(classes, per_class)},
              "confusion_matrix": matrix.tolist()}
    if levels is not None:
        result["accuracy_by_force_level_n"] = {float(d): float((predicted[levels == d] == y_true[levels == d]).mean())
                                               for d in np.unique(levels)}
    return result
