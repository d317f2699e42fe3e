"""Figures people would rather look at than read, and the conventions every Touchstone figure
follows: panels in a grid (never a strip), axes named with their quantity and unit, log axes
labelled with plain numbers."""
import math

import matplotlib

matplotlib.use("Agg")  # no display on training machines
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter  # noqa: E402

from data.units import unit_of  # noqa: E402

# How a column's unit word (data/units.py) is printed on an axis.
UNIT_SYMBOLS = {"m": "m", "cm": "cm", "mm": "mm", "um": "µm", "nm": "nm", "n": "N", "mn": "mN", "kn": "kN",
                "pa": "Pa", "kpa": "kPa", "mpa": "MPa", "ohm": "Ω", "kohm": "kΩ", "v": "V", "mv": "mV",
                "uv": "µV", "a": "A", "ma": "mA", "ua": "µA", "na": "nA", "s": "s", "ms": "ms", "us": "µs",
                "hz": "Hz", "khz": "kHz", "pf": "pF", "nf": "nF", "ff": "fF", "deg": "°", "rad": "rad",
                "degc": "°C", "kg": "kg", "counts": "counts"}


def quantity_words(column: str) -> str:
    """A column name without its unit word, in words: 'shear_x_n' -> 'shear x'."""
    known = UNIT_SYMBOLS.get(unit_of(column)) is not None
    return (str(column).rpartition("_")[0] if known else str(column)).replace("_", " ")


def quantity_label(column: str, what: str = "") -> str:
    """A column name as an axis label: 'depth_mm' -> 'depth (mm)', 'shear_x_n' -> 'shear x (N)';
    `what` goes in front ('true depth (mm)'). A name without a known unit word keeps its words
    and gets no unit: the unit is not known."""
    symbol = UNIT_SYMBOLS.get(unit_of(column))
    label = f"{what} {quantity_words(column)}".strip()
    return f"{label} ({symbol})" if symbol else label


def panel_grid(n: int, panel_width: float = 3.4, panel_height: float = 3.2, **subplots):
    """A figure of n panels in rows of at most 3 (4 from ten panels on), never a strip; returns
    (figure, the n axes in reading order). The grid's cells beyond n are not drawn."""
    n = max(int(n), 1)
    columns = n if n <= 3 else min(4, math.ceil(math.sqrt(n)))
    rows = math.ceil(n / columns)
    figure, axes = plt.subplots(rows, columns, figsize=(panel_width * columns, panel_height * rows),
                                squeeze=False, **subplots)
    axes = list(axes.ravel())
    for unused in axes[n:]:
        unused.remove()
    return figure, axes[:n]


def readable_log_axis(ax, which: str = "x") -> None:
    """Plain numbers on a log axis (0.01, 0.1, 1, 10, not 10^n), and over a short range more of
    them: 1, 2 and 5 x 10^n under two decades, 1, 2, 3 and 5 under 1.2, every integer multiple
    under half a decade (more would collide), so a reader never has to guess a value between two
    powers of ten. Call after the data is drawn."""
    axis = ax.xaxis if which == "x" else ax.yaxis
    low, high = ax.get_xlim() if which == "x" else ax.get_ylim()
    decades = math.log10(high / low) if low > 0 and high > low else 0.0
    subs = (tuple(range(1, 10)) if decades < 0.5 else (1, 2, 3, 5) if decades < 1.2 else (1, 2, 5) if decades < 2
            else (1,))
    axis.set_major_locator(LogLocator(base=10, subs=subs))
    axis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    axis.set_minor_formatter(NullFormatter())


def model_prefix(model: str | None) -> str:
    """'resmlp_seeds: ' in front of a figure's title, so a figure names the model it shows."""
    return f"{model}: " if model else ""


def parity_figure(y_true, y_pred, target_names, r2_by_target=None, split="test", model=None):
    """One panel per target: predictions against truth with the y = x line."""
    y_true, y_pred = np.asarray(y_true), np.asarray(y_pred)
    fig, axes = panel_grid(len(target_names))
    for k, (ax, name) in enumerate(zip(axes, target_names)):
        low = min(y_true[:, k].min(), y_pred[:, k].min())
        high = max(y_true[:, k].max(), y_pred[:, k].max())
        ax.plot([low, high], [low, high], color="0.6", lw=1, label="predicted = true")
        ax.scatter(y_true[:, k], y_pred[:, k], s=8, alpha=0.6)
        words = quantity_words(name)
        ax.set(title=words if r2_by_target is None else f"{words}: R² = {r2_by_target[name]:.3f}",
               xlabel=quantity_label(name, "true"), ylabel=quantity_label(name, "predicted"))
    fig.suptitle(f"{model_prefix(model)}predicted against true on the {split} split")
    fig.tight_layout()
    return fig


def residual_figure(y_true, y_pred, target_names, split="test", model=None):
    """Histogram of residuals (predicted - true) per target."""
    residual = np.asarray(y_pred) - np.asarray(y_true)
    fig, axes = panel_grid(len(target_names), panel_height=3.0)
    for k, (ax, name) in enumerate(zip(axes, target_names)):
        ax.hist(residual[:, k], bins=30, color="tab:gray")
        ax.axvline(0, color="k", lw=0.8)
        ax.locator_params(axis="x", nbins=5)   # wide residuals (pascals) print long numbers
        ax.set(xlabel=quantity_label(name, "predicted − true"), ylabel=f"{split} rows (count)")
    fig.suptitle(f"{model_prefix(model)}residuals on the {split} split")
    fig.tight_layout()
    return fig


def uncertainty_figure(y_true, mean, lower, upper, target_names, split="test", model=None):
    """Predictions with their calibrated 95 % intervals against the true value."""
    y_true = np.asarray(y_true)
    fig, axes = panel_grid(len(target_names))
    for k, (ax, name) in enumerate(zip(axes, target_names)):
        order = np.argsort(y_true[:, k])
        inside = (y_true[:, k] >= lower[:, k]) & (y_true[:, k] <= upper[:, k])
        ax.errorbar(y_true[order, k], mean[order, k],
                    yerr=[mean[order, k] - lower[order, k], upper[order, k] - mean[order, k]],
                    fmt=".", ms=3, lw=0.6, alpha=0.6, color="tab:blue")
        low, high = y_true[:, k].min(), y_true[:, k].max()
        ax.plot([low, high], [low, high], color="0.5", lw=1)
        ax.set(title=f"{quantity_words(name)}: {100 * inside.mean():.0f} % inside",
               xlabel=quantity_label(name, "true"), ylabel=quantity_label(name, "predicted"))
        readable_linear_ticks(ax)
    fig.suptitle(f"{model_prefix(model)}predictions with calibrated 95 % intervals on the {split} split\n"
                 "(share of true values inside their interval in each title)")
    fig.tight_layout()
    return fig


def readable_linear_ticks(ax, most: int = 5) -> None:
    """At most `most` ticks per linear axis, large or small numbers as a power of ten at the axis'
    end: a pressure panel's six-digit pascals collided on a 3.4-inch panel. Call after drawing."""
    ax.locator_params(axis="both", nbins=most)
    ax.ticklabel_format(axis="both", style="sci", scilimits=(-3, 4), useMathText=True)


def importance_figure(names, importances, title, top=20):
    order = np.argsort(importances)[::-1][:top]
    fig, ax = plt.subplots(figsize=(6, 0.28 * len(order) + 1.2))
    ax.barh(np.arange(len(order))[::-1], np.asarray(importances)[order], color="tab:green")
    ax.set_yticks(np.arange(len(order))[::-1], [names[i] for i in order], fontsize=7)
    ax.set(title=title, xlabel="share of the impurity decrease (–)", ylabel="feature")
    fig.tight_layout()
    return fig


def correlation_figure(matrix, labels):
    fig, ax = plt.subplots(figsize=(0.45 * len(labels) + 2.5, 0.45 * len(labels) + 1.8))
    image = ax.imshow(matrix, cmap="coolwarm", vmin=-1, vmax=1)
    ax.set_xticks(range(len(labels)), labels, rotation=90, fontsize=7)
    ax.set_yticks(range(len(labels)), labels, fontsize=7)
    ax.set(xlabel="target or feature", ylabel="target or feature")
    fig.colorbar(image, ax=ax, shrink=0.8, label="Pearson correlation r (–)")
    ax.set_title("Correlation of the targets and the most important features")
    fig.tight_layout()
    return fig


def identifiability_figure(identifiability):
    """Mean position sigma and |error| over the sheet; depth and pressure sigma/|error| vs depth."""
    edges = identifiability["xy_edges_mm"]
    extent = (edges[0], edges[-1], edges[0], edges[-1])
    fig, axes = panel_grid(4, panel_width=4.6, panel_height=3.6)
    for ax, key, title in ((axes[0], "position_sigma_mm", "predicted σ of the position"),
                           (axes[1], "position_abs_error_mm", "|error| of the position")):
        image = ax.imshow(np.asarray(identifiability[key], dtype=float), origin="lower", extent=extent, cmap="magma")
        ax.set(title=title, xlabel="x (mm)", ylabel="y (mm)")
        fig.colorbar(image, ax=ax, shrink=0.8, label=f"mean {title.split(' of')[0]} (mm)")
    depth_edges = np.asarray(identifiability["depth_edges_mm"])
    centres = (depth_edges[:-1] + depth_edges[1:]) / 2
    for ax, target in zip(axes[2:], ("depth_mm", "pressure_pa")):
        row = identifiability["by_depth"][target]
        ax.plot(centres, row["sigma"], "o-", label="mean predicted σ")
        ax.plot(centres, row["abs_error"], "s--", label="mean |error|")
        ax.set(title=f"{quantity_words(target)}: σ and |error| against depth", xlabel="depth (mm)",
               ylabel=quantity_label(target, "σ or |error| of"))
        ax.legend(fontsize=8)
    fig.suptitle("Where the test presses are identifiable: mean per cell of the sheet and per depth")
    fig.tight_layout()
    return fig


def confusion_figure(matrix, classes, title, samples="windows"):
    """Row-normalised confusion matrix with counts in the cells; `samples` names what was counted
    (a table's rows, a recording's windows)."""
    matrix = np.asarray(matrix, dtype=float)
    share = matrix / np.maximum(matrix.sum(axis=1, keepdims=True), 1)
    size = 0.45 * len(classes) + 2.5
    fig, ax = plt.subplots(figsize=(size + 1.0, size))
    image = ax.imshow(share, cmap="Blues", vmin=0, vmax=1)
    ax.set_xticks(range(len(classes)), classes, rotation=90, fontsize=7)
    ax.set_yticks(range(len(classes)), classes, fontsize=7)
    if len(classes) <= 20:
        for i in range(len(classes)):
            for j in range(len(classes)):
                if matrix[i, j]:
                    ax.text(j, i, int(matrix[i, j]), ha="center", va="center", fontsize=6,
                            color="white" if share[i, j] > 0.5 else "black")
    fig.colorbar(image, ax=ax, shrink=0.8, label=f"share of the true class's {samples} (–)")
    ax.set(xlabel="predicted class", ylabel="true class", title=title)
    fig.tight_layout()
    return fig
