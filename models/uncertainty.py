"""Prediction intervals that say how sure a model is, and a check that they mean it.

A model with `predict_std(X) -> (mean, sigma_total)` gets intervals mean +/- z sigma. The raw
interval assumes Gaussian, well-estimated errors; split-conformal calibration (Vovk et al.
2005; Lei et al., JASA 113, 2018) makes it distribution-free: on held-out calibration data take
the normalised scores |y - mean| / sigma and their ceil((n + 1)(1 - alpha)) / n empirical
quantile q, per target; then mean +/- q sigma covers a new point with probability >= 1 - alpha
(exchangeable data). With fewer calibration rows than the quantile needs (19 at 95 %),
`IntervalMixin.calibrate` keeps the raw Gaussian scale and says so (`calibration_note_`);
`conformal_quantile` itself refuses them.

When rows come in recordings that share effects (a drift walk, one unloaded frame), rows are
not exchangeable but whole recordings are: pool the scores of several recordings for q, and
check the coverage a new recording gets by leaving each recording out in turn
(`leave_one_group_out_coverage`; Barber et al., Ann. Stat. 49, 2021, jackknife+ idea at the
group level) - the spread over recordings is what one test recording's coverage varies by.
"""
import numpy as np
from scipy.stats import norm

from common.errors import InputError

Z_95 = 1.959963984540054


def calibration_rows_needed(alpha: float = 0.05) -> int:
    """The fewest calibration rows whose conformal quantile at 1 - alpha is one of them."""
    return int(np.ceil((1 - alpha) / alpha - 1e-9))


def conformal_quantile(scores: np.ndarray, alpha: float = 0.05) -> np.ndarray:
    """Per-column split-conformal quantile of (n, n_targets) non-negative scores."""
    scores = np.asarray(scores, dtype=np.float64)
    n = scores.shape[0]
    rank = int(np.ceil((n + 1) * (1.0 - alpha)))
    if rank > n:
        raise InputError(f"conformal calibration at {100 * (1 - alpha):.0f} % needs at least "
                         f"{calibration_rows_needed(alpha)} calibration rows, got {n}")
    return np.sort(scores, axis=0)[rank - 1]


def normalised_scores(y, mean, sigma) -> np.ndarray:
    """|y - mean| / sigma, with sigma floored so a zero-spread prediction cannot divide by zero."""
    sigma = np.maximum(np.asarray(sigma, dtype=np.float64), 1e-12 * (np.abs(mean).max() + 1.0))
    return np.abs(np.asarray(y) - mean) / sigma


def leave_one_group_out_coverage(scores, groups, alpha: float = 0.05) -> np.ndarray:
    """(n_groups, n_targets): the share of each group's scores within the conformal quantile
    of the other groups' scores (needs two groups or more)."""
    scores, groups = np.asarray(scores, dtype=np.float64), np.asarray(groups)
    names = np.unique(groups)
    if len(names) < 2:
        raise InputError(f"leave-one-group-out coverage needs at least 2 groups, got {len(names)}")
    return np.array([(scores[groups == g] <= conformal_quantile(scores[groups != g], alpha)).mean(axis=0)
                     for g in names])


def coverage(y, lower, upper) -> np.ndarray:
    """Share of rows whose truth lies in [lower, upper], per target."""
    y = np.asarray(y)
    return ((y >= lower) & (y <= upper)).mean(axis=0)


class IntervalMixin:
    """Adds calibrate / predict_interval to an estimator that implements predict_std."""

    @property
    def calibrated(self) -> bool:
        """Whether `calibrate` has set the interval scale (an exported graph then gives intervals)."""
        return getattr(self, "conformal_scale_", None) is not None

    def calibrate(self, X, y, alpha: float = 0.05):
        """The conformal scale per target from calibration rows (X, y); with too few of them, the
        raw scale z_{1 - alpha/2} (1.96 at 95 %) and `calibration_note_` saying why."""
        mean, sigma = self.predict_std(X)
        self.alpha_ = alpha
        needed = calibration_rows_needed(alpha)
        if len(mean) < needed:
            self.conformal_scale_ = np.full(mean.shape[1], norm.ppf(1 - alpha / 2))
            self.calibration_note_ = (f"too few calibration rows for a conformal {100 * (1 - alpha):.0f} % interval "
                                      f"({len(mean)} < {needed}): intervals are the uncalibrated mean +/- "
                                      f"{self.conformal_scale_[0]:.2f} sigma")
            return self
        self.conformal_scale_ = conformal_quantile(normalised_scores(y, mean, sigma), alpha)
        self.calibration_note_ = None
        return self

    def predict_interval(self, X, calibrated: bool = True):
        """(mean, lower, upper): raw mean +/- 1.96 sigma, or the conformal mean +/- q sigma."""
        mean, sigma = self.predict_std(X)
        scale = self.conformal_scale_ if calibrated else Z_95
        return mean, mean - scale * sigma, mean + scale * sigma
