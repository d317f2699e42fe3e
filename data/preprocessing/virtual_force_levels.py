"""Virtual force-level data generation: the seed paper's Algorithm 1, faithfully.

Training windows exist only at the recorded force levels. For each target level d_tar that
was never recorded:
  1. its adjacent recorded levels: d_i = max{d < d_tar}, d_j = min{d > d_tar};
  2. per window, f1 = mean |X_TE| (triboelectric), f3 = max X_PR (piezoresistive, in newtons),
     and, reported only, f2 = max cumsum X_TE - min cumsum X_TE;
  3. per class, a cubic F fitted over that class's training windows with f1 = F(f3);
  4. every window X of class c at d_i or d_j becomes a virtual window at d_tar:
     X_TE * eta_TE with eta_TE = F_c(d_tar) / f1(X), and X_PR * eta_PR with eta_PR = d_tar / f3(X).
Both neighbours contribute equally (all their windows, once each).

Defined behaviour where the algorithm is undefined:
- a target outside the recorded range (no neighbour on one side): one-line error;
- a class with fewer than 4 distinct f3 values cannot determine a cubic: the degree drops to
  (distinct values - 1), and a class with a single f3 value is an error;
- windows with f1 = 0 or f3 <= 0 cannot be scaled: they are skipped and counted, and so are
  windows whose scale factors or scaled values overflow (f3 = 5e-324 gives eta_PR = inf);
- F_c(d_tar) <= 0 (a cubic extrapolating below zero): eta_TE = 0 is not physical, so the
  class is skipped for that level and counted. No NaN or inf window is ever produced.
"""
import numpy as np

from common.errors import InputError


def window_features(windows: np.ndarray, te: int, pr: int):
    """f1 = mean |X_TE|, f2 = range of cumsum X_TE, f3 = max X_PR per window."""
    x_te = windows[:, te].astype(np.float64)
    cumulative = np.cumsum(x_te, axis=1)
    return (np.abs(x_te).mean(axis=1), cumulative.max(axis=1) - cumulative.min(axis=1),
            windows[:, pr].astype(np.float64).max(axis=1))


def adjacent_levels(recorded, target: float):
    below = [d for d in recorded if d < target]
    above = [d for d in recorded if d > target]
    if not below or not above:
        raise InputError(f"virtual force level {target} N lies outside the recorded levels "
                         f"{sorted(recorded)}: Algorithm 1 needs a recorded level on each side")
    return max(below), min(above)


def fit_cubic(f3: np.ndarray, f1: np.ndarray, class_name) -> np.poly1d:
    distinct = np.unique(np.round(f3, 12)).size
    if distinct < 2:
        raise InputError(f"class {class_name}: every window has the same f3 = {f3[0]:.4g}; "
                         "no curve f1 = F(f3) can be fitted")
    return np.poly1d(np.polyfit(f3, f1, min(3, distinct - 1)))


def virtual_force_levels(windows, labels, levels, target_levels, te=0, pr=1):
    """Algorithm 1. Returns (virtual windows, their labels, their levels, report dict)."""
    windows = np.asarray(windows)
    labels, levels = np.asarray(labels), np.asarray(levels, dtype=np.float64)
    recorded = sorted(set(levels.tolist()))
    f1, f2, f3 = window_features(windows, te, pr)
    scalable = (f1 > 0) & (f3 > 0)
    out_windows, out_labels, out_levels = [], [], []
    report = {"recorded_levels": recorded, "targets": {}, "skipped_windows_zero_f1_or_f3": int((~scalable).sum()),
              "skipped_windows_overflow": 0,
              "mean_f2_by_level": {float(d): float(f2[levels == d].mean()) for d in recorded}}
    curves = {}
    for c in np.unique(labels):
        rows = (labels == c) & scalable
        curves[c] = fit_cubic(f3[rows], f1[rows], c) if rows.any() else None
    for target in target_levels:
        target = float(target)
        low, high = adjacent_levels(recorded, target)
        made, skipped_classes = 0, []
        for c, curve in curves.items():
            if curve is None:
                skipped_classes.append(str(c))
                continue
            level_f1 = float(curve(target))
            if not np.isfinite(level_f1) or level_f1 <= 0:
                skipped_classes.append(str(c))
                continue
            rows = np.flatnonzero((labels == c) & scalable & ((levels == low) | (levels == high)))
            virtual = windows[rows].astype(np.float64)
            with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
                virtual[:, te] *= (level_f1 / f1[rows])[:, None]
                virtual[:, pr] *= (target / f3[rows])[:, None]
            finite = np.isfinite(virtual.astype(windows.dtype)).all(axis=(1, 2))
            report["skipped_windows_overflow"] += int((~finite).sum())
            rows, virtual = rows[finite], virtual[finite]
            out_windows.append(virtual.astype(windows.dtype))
            out_labels.append(labels[rows])
            out_levels.append(np.full(rows.size, target))
            made += rows.size
        report["targets"][target] = {"neighbours": [low, high], "windows": made, "skipped_classes": skipped_classes}
    if not out_windows:
        return windows[:0], labels[:0], levels[:0], report
    return np.concatenate(out_windows), np.concatenate(out_labels), np.concatenate(out_levels), report
