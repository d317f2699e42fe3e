"""Figures people would rather look at than read: predicted vs true per target."""
import matplotlib

matplotlib.use("Agg")  # no display on training machines
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def parity_figure(y_true, y_pred, target_names, r2_by_target=None):
    """One panel per target: predictions against truth with the y = x line."""
    y_true, y_pred = np.asarray(y_true), np.asarray(y_pred)
    n = len(target_names)
    fig, axes = plt.subplots(1, n, figsize=(3.4 * n, 3.4), squeeze=False)
    for k, (ax, name) in enumerate(zip(axes[0], target_names)):
        low = min(y_true[:, k].min(), y_pred[:, k].min())
        high = max(y_true[:, k].max(), y_pred[:, k].max())
        ax.plot([low, high], [low, high], color="0.6", lw=1)
        ax.scatter(y_true[:, k], y_pred[:, k], s=8, alpha=0.6)
        title = name if r2_by_target is None else f"{name}  R²={r2_by_target[name]:.3f}"
        ax.set(title=title, xlabel="true", ylabel="predicted")
    fig.tight_layout()
    return fig


def residual_figure(y_true, y_pred, target_names):
    """Histogram of residuals (predicted - true) per target."""
    residual = np.asarray(y_pred) - np.asarray(y_true)
    n = len(target_names)
    fig, axes = plt.subplots(1, n, figsize=(3.4 * n, 3.0), squeeze=False)
    for k, (ax, name) in enumerate(zip(axes[0], target_names)):
        ax.hist(residual[:, k], bins=30, color="tab:gray")
        ax.axvline(0, color="k", lw=0.8)
        ax.set(title=f"{name}: residuals", xlabel="predicted - true", ylabel="count")
    fig.tight_layout()
    return fig


def uncertainty_figure(y_true, mean, lower, upper, target_names):
    """Predictions with their calibrated 95 % intervals against the true value."""
    y_true = np.asarray(y_true)
    n = len(target_names)
    fig, axes = plt.subplots(1, n, figsize=(3.4 * n, 3.4), squeeze=False)
    for k, (ax, name) in enumerate(zip(axes[0], target_names)):
        order = np.argsort(y_true[:, k])
        inside = (y_true[:, k] >= lower[:, k]) & (y_true[:, k] <= upper[:, k])
        ax.errorbar(y_true[order, k], mean[order, k],
                    yerr=[mean[order, k] - lower[order, k], upper[order, k] - mean[order, k]],
                    fmt=".", ms=3, lw=0.6, alpha=0.6, color="tab:blue")
        low, high = y_true[:, k].min(), y_true[:, k].max()
        ax.plot([low, high], [low, high], color="0.5", lw=1)
        ax.set(title=f"{name}: {100 * inside.mean():.0f} % inside 95 % PI", xlabel="true", ylabel="predicted")
    fig.tight_layout()
    return fig


def importance_figure(names, importances, title, top=20):
    order = np.argsort(importances)[::-1][:top]
    fig, ax = plt.subplots(figsize=(6, 0.28 * len(order) + 1))
    ax.barh(np.arange(len(order))[::-1], np.asarray(importances)[order], color="tab:green")
    ax.set_yticks(np.arange(len(order))[::-1], [names[i] for i in order], fontsize=7)
    ax.set(title=title, xlabel="mean impurity decrease")
    fig.tight_layout()
    return fig


def correlation_figure(matrix, labels):
    fig, ax = plt.subplots(figsize=(0.45 * len(labels) + 2, 0.45 * len(labels) + 1.5))
    image = ax.imshow(matrix, cmap="coolwarm", vmin=-1, vmax=1)
    ax.set_xticks(range(len(labels)), labels, rotation=90, fontsize=7)
    ax.set_yticks(range(len(labels)), labels, fontsize=7)
    fig.colorbar(image, ax=ax, shrink=0.8)
    ax.set_title("correlation: targets and top features")
    fig.tight_layout()
    return fig


def identifiability_figure(identifiability):
    """Mean position sigma and |error| over the sheet; depth and pressure sigma/|error| vs depth."""
    edges = identifiability["xy_edges_mm"]
    extent = (edges[0], edges[-1], edges[0], edges[-1])
    fig, axes = plt.subplots(1, 4, figsize=(16, 3.6))
    for ax, key, title in ((axes[0], "position_sigma_mm", "mean position σ (mm)"),
                           (axes[1], "position_abs_error_mm", "mean position |error| (mm)")):
        image = ax.imshow(np.asarray(identifiability[key], dtype=float), origin="lower", extent=extent, cmap="magma")
        ax.set(title=title, xlabel="x (mm)", ylabel="y (mm)")
        fig.colorbar(image, ax=ax, shrink=0.8)
    depth_edges = np.asarray(identifiability["depth_edges_mm"])
    centres = (depth_edges[:-1] + depth_edges[1:]) / 2
    for ax, target in zip(axes[2:], ("depth_mm", "pressure_pa")):
        row = identifiability["by_depth"][target]
        ax.plot(centres, row["sigma"], "o-", label="mean σ")
        ax.plot(centres, row["abs_error"], "s--", label="mean |error|")
        ax.set(title=f"{target} vs depth", xlabel="depth (mm)", ylabel=target)
        ax.legend()
    fig.tight_layout()
    return fig


def confusion_figure(matrix, classes, title):
    """Row-normalised confusion matrix with counts in the cells."""
    matrix = np.asarray(matrix, dtype=float)
    share = matrix / np.maximum(matrix.sum(axis=1, keepdims=True), 1)
    size = 0.45 * len(classes) + 2.5
    fig, ax = plt.subplots(figsize=(size, size))
    ax.imshow(share, cmap="Blues", vmin=0, vmax=1)
    ax.set_xticks(range(len(classes)), classes, rotation=90, fontsize=7)
    ax.set_yticks(range(len(classes)), classes, fontsize=7)
    if len(classes) <= 20:
        for i in range(len(classes)):
            for j in range(len(classes)):
                if matrix[i, j]:
                    ax.text(j, i, int(matrix[i, j]), ha="center", va="center", fontsize=6,
                            color="white" if share[i, j] > 0.5 else "black")
    ax.set(xlabel="predicted", ylabel="true", title=title)
    fig.tight_layout()
    return fig
