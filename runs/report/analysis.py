"""The rubber12 paper's analysis of a fitted regressor, and what it left open.

- coverage of the nominal 95 % interval on the test split, raw and after split-conformal
  calibration, per target;
- Spearman correlation between predicted sigma_total and |error| (does the model know when
  it is wrong?);
- the identifiability map: mean sigma and mean |error| over the x-y plane and over depth;
- the feature-group ablation: retrain one model with each feature group removed, report the
  change in test R^2 per target.
"""
import numpy as np
from scipy.stats import spearmanr
from sklearn.base import clone
from sklearn.metrics import r2_score

from common.progress import progress as progress_bar
from data.preprocessing.features import enabled_groups
from models.capabilities import fit
from models.uncertainty import coverage


def interval_report(model, X_test, y_test, targets) -> dict:
    """Coverage before/after calibration, mean interval widths, Spearman(sigma, |error|)."""
    mean, sigma = model.predict_std(X_test)
    report = {"nominal": 0.95, "conformal_scale": dict(zip(targets, map(float, model.conformal_scale_)))}
    for name, calibrated in (("raw", False), ("calibrated", True)):
        _, lower, upper = model.predict_interval(X_test, calibrated=calibrated)
        report[f"coverage_{name}"] = dict(zip(targets, map(float, coverage(y_test, lower, upper))))
        report[f"mean_width_{name}"] = dict(zip(targets, map(float, (upper - lower).mean(axis=0))))
    error = np.abs(y_test - mean)
    report["spearman_sigma_vs_abs_error"] = {
        t: float(spearmanr(sigma[:, k], error[:, k]).statistic) if np.ptp(sigma[:, k]) > 0 else float("nan")
        for k, t in enumerate(targets)}
    return report, mean, sigma


def identifiability_map(xy_mm, depth_mm, sigma, error, targets, bins=5, extent_mm=(0.0, 50.0), depth_bins=6):
    """Mean sigma and mean |error| per x-y cell (position: the root-sum-square of x and y) and per
    depth bin (depth and pressure). Empty cells are NaN."""
    ix, iy = targets.index("x_mm"), targets.index("y_mm")
    position_sigma = np.hypot(sigma[:, ix], sigma[:, iy])
    position_error = np.hypot(error[:, ix], error[:, iy])
    edges = np.linspace(*extent_mm, bins + 1)
    col = np.clip(np.digitize(xy_mm[:, 0], edges) - 1, 0, bins - 1)
    row = np.clip(np.digitize(xy_mm[:, 1], edges) - 1, 0, bins - 1)

    def cell_means(values):
        total, count = np.zeros((bins, bins)), np.zeros((bins, bins))
        np.add.at(total, (row, col), values)
        np.add.at(count, (row, col), 1)
        return np.divide(total, count, out=np.full_like(total, np.nan), where=count > 0)

    depth_edges = np.linspace(depth_mm.min(), depth_mm.max() + 1e-9, depth_bins + 1)
    which = np.clip(np.digitize(depth_mm, depth_edges) - 1, 0, depth_bins - 1)
    by_depth = {}
    for t in ("depth_mm", "pressure_pa"):
        k = targets.index(t)
        by_depth[t] = {
            "sigma": [float(sigma[which == b, k].mean()) if (which == b).any() else float("nan") for b in range(depth_bins)],
            "abs_error": [float(error[which == b, k].mean()) if (which == b).any() else float("nan") for b in range(depth_bins)]}
    return {"xy_edges_mm": edges.tolist(), "position_sigma_mm": cell_means(position_sigma).tolist(),
            "position_abs_error_mm": cell_means(position_error).tolist(),
            "depth_edges_mm": depth_edges.tolist(), "by_depth": by_depth}


def edge_vs_centre(xy_mm, values, side_mm=50.0, border_mm=12.5) -> dict:
    """Mean of `values` within `border_mm` of an edge vs in the middle of the sheet."""
    near = (np.minimum(xy_mm, side_mm - xy_mm) <= border_mm).any(axis=1)
    return {"edge": float(values[near].mean()) if near.any() else float("nan"),
            "centre": float(values[~near].mean()) if (~near).any() else float("nan")}


def feature_ablation(estimator, datamodule, progress=True) -> dict:
    """Test R^2 per target with all feature groups, and its change with each group removed."""
    targets = datamodule.target_names
    groups = enabled_groups(datamodule.features)
    y_train, y_test = datamodule.y[datamodule.train_idx], datamodule.y[datamodule.test_idx]
    X_val_rows, y_val = datamodule.val_idx, datamodule.y[datamodule.val_idx]

    def test_r2(chosen):
        X, _ = datamodule.features_for(chosen)
        model = fit(clone(estimator), X[datamodule.train_idx], y_train, X[X_val_rows], y_val)
        predicted = model.predict(X[datamodule.test_idx]).reshape(y_test.shape)
        return np.array([r2_score(y_test[:, k], predicted[:, k]) for k in range(len(targets))])

    full = test_r2(groups)
    result = {"all_groups_r2": dict(zip(targets, map(float, full))), "delta_r2_without": {}}
    for group in progress_bar([g for g in groups if len(groups) > 1], desc="ablation", unit="refits", enabled=progress):
        delta = test_r2([g for g in groups if g != group]) - full
        result["delta_r2_without"][group] = dict(zip(targets, map(float, delta)))
    return result


def format_ablation(ablation: dict) -> str:
    targets = list(ablation["all_groups_r2"])
    lines = [f"{'without':<15}" + "".join(f"{t:>13}" for t in targets)]
    lines.append(f"{'(all: R2)':<15}" + "".join(f"{ablation['all_groups_r2'][t]:>13.4f}" for t in targets))
    for group, row in ablation["delta_r2_without"].items():
        lines.append(f"{group:<15}" + "".join(f"{row[t]:>+13.4f}" for t in targets))
    return "\n".join(lines)
