"""The epoch count chosen on folds (`epoch_selection=folds`, models/timeseries_classifier.py).

Each stratified fold of the training recordings trains as the refit will and predicts its held-out
recordings at every epoch; these functions pool those predictions into one curve over every
training window and pick the epoch the refit trains for. Kept apart from the training loop: they
are plain arithmetic on the folds' probabilities.
"""
import numpy as np

# Each epoch is scored by the pooled held-out accuracy (and loss) averaged over it and the epochs
# before it, this many in all: on ArrowHead's 36 recordings the single best epoch was a spike
# (seed 0: epoch 67, pooled 0.83, its refit 0.73 on test) where windows of 5-21 epochs chose
# 148-160 (refit 0.82-0.84); trailing, so a curve still rising when the budget ends chooses its
# last epoch (docs/training_recipes.md).
FOLD_CURVE_WINDOW = 11


def pooled_curve(folds, curves, n_windows: int, n_classes: int) -> np.ndarray:
    """Every epoch's held-out probabilities of every training window [epochs, windows, classes]
    (float32), each window predicted by the fold that held it out; a fold that stopped early keeps
    its last predictions for the later epochs. Epochs x windows x classes, 1500 x 3,000 x 10,
    would be 180 MB: a set of many windows per recording should lower trainer.max_epochs."""
    n_epochs = max(len(curve) for curve in curves)
    proba = np.zeros((n_epochs, n_windows, n_classes), dtype=np.float32)
    for (_, held_rows), curve in zip(folds, curves):
        proba[:, held_rows] = np.concatenate([curve, np.repeat(curve[-1:], n_epochs - len(curve), axis=0)])
    return proba


def trailing_mean(values, window: int) -> np.ndarray:
    """Each value replaced by the mean of it and the values before it, `window` in all (fewer at the start)."""
    sums = np.concatenate([[0.0], np.cumsum(values)])
    index = np.arange(len(values))
    low = np.maximum(index + 1 - window, 0)
    return (sums[index + 1] - sums[low]) / (index + 1 - low)


def held_out_scores(curve, y):
    """Accuracy and mean cross-entropy at every epoch of held-out probabilities `curve`
    (epochs, windows, classes) against labels `y`."""
    accuracy = (curve.argmax(axis=2) == y).mean(axis=1)
    loss = -np.log(np.clip(curve[:, np.arange(len(y)), y], 1e-12, None)).mean(axis=1)
    return accuracy, loss


def best_epoch(proba, y):
    """(index of the chosen epoch, the smoothed accuracy curve, the smoothed loss curve): the best
    pooled held-out accuracy, ties broken by the lower loss, each averaged over FOLD_CURVE_WINDOW epochs."""
    accuracy, loss = (trailing_mean(score, FOLD_CURVE_WINDOW) for score in held_out_scores(proba, y))
    return max(range(len(accuracy)), key=lambda e: (accuracy[e], -loss[e])), accuracy, loss


def each_folds_best_epoch(folds, curves, y) -> list[int]:
    """Each fold alone: the epoch (1-based) of its own best held-out accuracy (ties: lower loss),
    unsmoothed, to show how far the folds' choices spread."""
    best = []
    for (_, held_rows), curve in zip(folds, curves):
        accuracy, loss = held_out_scores(curve, y[held_rows])
        best.append(max(range(len(curve)), key=lambda e: (accuracy[e], -loss[e])) + 1)
    return best
