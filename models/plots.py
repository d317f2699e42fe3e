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
