"""Validation-guided weighting of candidate models (seed eq. 18-20) and the blend's uncertainty.

Each candidate is fitted on the training split and scored on the validation split:
s_m = max(R^2_val, 0), w_m = s_m / sum_j s_j, prediction = sum_m w_m yhat_m. Weights are per
target by default (a model can be best at depth and worst at x); `per_target=False` uses the
candidates' mean R^2 over targets. `mode="argmax"` keeps only the best candidate.

When every candidate scores R^2 <= 0 on a target there is nothing to weight by: the blend
falls back to equal weights for that target and lists it in `fallback_targets_` (the run's
metrics report it), never dividing by zero.

Uncertainty: sigma_model^2 = sum_m w_m (sigma_model,m^2 + (yhat_m - yhat)^2), the weighted
mixture's spread (fold spread of each K-fold candidate plus the candidates' disagreement);
sigma_data^2 from the blend's out-of-fold residuals when every candidate is K-fold blended,
else from validation residuals.

`weights="stacking"` replaces the seed's rule, which gives every reasonable candidate about a
third and can end worse than its best candidate, by a super learner (see ValidationWeightedBlend).
"""
import copy
import time

import numpy as np
from scipy.optimize import nnls
from sklearn.base import clone
from sklearn.metrics import r2_score
from sklearn.utils.validation import check_is_fitted, validate_data

from common.errors import InputError
from common.progress import progress
from data.splits.indices import carve_validation
from models.capabilities import capabilities, declare
from models.epoch_callback import member_callback
from models.estimator_base import TouchstoneRegressor
from models.kfold_blend import KFoldBlend
from models.uncertainty import IntervalMixin

MODES = ("weighted", "argmax")
WEIGHTS = ("paper", "stacking")


def validation_weights(scores: np.ndarray, mode: str = "weighted"):
    """(n_models, n_targets) validation R^2 -> (weights, fallback target columns)."""
    if mode not in MODES:
        raise InputError(f"model.mode must be one of {', '.join(MODES)}, got '{mode}'")
    scores = np.nan_to_num(np.asarray(scores, dtype=np.float64), nan=0.0)
    positive = np.maximum(scores, 0.0)
    if mode == "argmax":
        positive = (scores == scores.max(axis=0, keepdims=True)) & (scores > 0)
        positive = positive / np.maximum(positive.sum(axis=0, keepdims=True), 1)
    total = positive.sum(axis=0)
    fallback = np.flatnonzero(total <= 0)
    with np.errstate(under="ignore"):  # a denormal R^2 (5e-324) over a total of 2 is a weight of 0
        weights = np.divide(positive, total, out=np.full_like(positive, 1.0 / len(scores)), where=total > 0)
    return weights, fallback


def stacking_weights(predictions: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Super-learner weights of one target: non-negative least squares of the candidates'
    out-of-fold predictions (n_rows, n_models) on the truth (n_rows,), constrained to sum to 1
    (a heavily weighted extra row asks for it; the result is then normalised exactly).
    van der Laan, Polley & Hubbard, "Super learner", Stat. Appl. Genet. Mol. Biol. 6 (2007)."""
    scale = np.sqrt(np.mean(predictions ** 2)) or 1.0
    penalty = 1e3 * scale * np.sqrt(len(y))
    A = np.vstack([predictions, np.full((1, predictions.shape[1]), penalty)])
    b = np.append(y, penalty)
    weights, _ = nnls(A, b, maxiter=50 * A.shape[1])
    total = weights.sum()
    if not np.isfinite(total) or total <= 0:  # degenerate: every candidate useless; share equally
        return np.full(predictions.shape[1], 1.0 / predictions.shape[1])
    return weights / total


class ValidationWeightedBlend(IntervalMixin, TouchstoneRegressor):
    """Candidates fitted on the training split, blended with weights chosen without the test split.

    weights="paper": the seed's rule (eq. 18-20) from validation R^2 (`mode`, `per_target`).
    weights="stacking": per target, the super learner on the candidates' out-of-fold predictions
    (every candidate must be K-fold blended). Then, per target, if the stacked blend scores below
    its best candidate on validation, that candidate alone is used for the target (listed in
    `stacking_fallback_targets_`): on validation the blend is never worse than its best candidate.
    Without an explicit validation split the blend carves its own (`val_fraction`, grouped when
    groups are given).
    """

    def __init__(self, candidates=None, mode="weighted", per_target=True, weights="paper", val_fraction=0.15,
                 seed=0):
        self.candidates = candidates
        self.mode = mode
        self.per_target = per_target
        self.weights = weights
        self.val_fraction = val_fraction
        self.seed = seed

    def __sklearn_tags__(self):
        trees = any(capabilities(e).importances for e in (self.candidates or {}).values())
        tags = declare(super().__sklearn_tags__(), intervals=True, weighs_candidates=True, importances=trees,
                       size="n_parameters")
        tags.target_tags.multi_output = True
        return tags

    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
        if not self.candidates:
            raise InputError("model.candidates is empty: name at least one candidate model")
        if self.weights not in WEIGHTS:
            raise InputError(f"model.weights must be one of {', '.join(WEIGHTS)}, got '{self.weights}'")
        if self.weights == "stacking" and self.mode != "weighted":
            raise InputError("model.mode=argmax keeps one candidate; it does not combine with model.weights=stacking")
        missing = [n for n, e in self.candidates.items() if not isinstance(e, KFoldBlend)]
        if self.weights == "stacking" and missing:  # said before minutes of fitting, not after
            raise InputError(f"model.weights=stacking needs out-of-fold predictions, which candidate(s) "
                             f"{', '.join(missing)} lack: K-fold blend them (models/kfold_blend.py) or use "
                             "model.weights=paper")
        X, y = validate_data(self, X, y, multi_output=True, y_numeric=True, dtype=np.float64)
        self.single_output_ = y.ndim == 1
        if X_val is None or y_val is None:  # carve validation rows from the training rows
            if len(X) < 3:
                raise InputError(f"the weighted blend needs at least 3 samples to carve a validation split, "
                                 f"got {len(X)} sample" + ("" if len(X) == 1 else "s"))
            fit_rows, val_rows = carve_validation(len(X), self.val_fraction, self.seed, groups)
            X, y, X_val, y_val = X[fit_rows], y[fit_rows], X[val_rows], y[val_rows]
            groups = None if groups is None else np.asarray(groups)[fit_rows]
        X_val = validate_data(self, X_val, reset=False, dtype=np.float64)
        y2 = y.reshape(len(y), -1)
        y_val2 = np.asarray(y_val, dtype=np.float64).reshape(len(y_val), -1)
        self.models_, self.fit_time_s_, scores, val_predictions = {}, {}, [], []
        for name, estimator in progress(self.candidates.items(), desc="blend candidates", unit="models"):
            start = time.perf_counter()
            model = clone(estimator).fit(X, y, X_val, y_val, epoch_callback=member_callback(epoch_callback, name),
                                         groups=groups)
            self.fit_time_s_[name] = time.perf_counter() - start
            predicted = model.predict(X_val).reshape(y_val2.shape)
            scores.append([r2_score(y_val2[:, k], predicted[:, k]) if len(y_val2) > 1 else np.nan
                           for k in range(y_val2.shape[1])])
            val_predictions.append(predicted)
            self.models_[name] = model
        self.val_r2_ = np.asarray(scores)
        self.val_predictions_, self.y_val_, self.y_fit_ = np.stack(val_predictions), y_val2, y2
        self._choose_weights()
        return self

    def _choose_weights(self) -> None:
        """weights_ (and sigma_data) from the fitted candidates by the configured rule."""
        models, y2, y_val2 = list(self.models_.values()), self.y_fit_, self.y_val_
        self.stacking_fallback_targets_ = []
        if self.weights == "paper":
            ranking = self.val_r2_ if self.per_target else np.repeat(
                np.nanmean(self.val_r2_, axis=1, keepdims=True), self.val_r2_.shape[1], axis=1)
            self.weights_, self.fallback_targets_ = validation_weights(ranking, self.mode)
        else:
            self.weights_, self.fallback_targets_ = self._stacking(models, y2, self.val_predictions_, y_val2), []
        self.val_residual_ = ((y_val2[None] - self.val_predictions_) ** 2).mean(axis=1)
        if all(hasattr(m, "out_of_fold_") for m in models):
            blended = sum(self.weights_[i] * m.out_of_fold_ for i, m in enumerate(models))
            self.data_variance_ = ((y2 - blended) ** 2).mean(axis=0)
        else:
            self.data_variance_ = (self.weights_ * self.val_residual_).sum(axis=0)

    def reweighted(self, weights: str) -> "ValidationWeightedBlend":
        """A copy that shares the fitted candidates and weighs them by another rule (for
        comparing rules on the same fit: bench/blend_weights.py)."""
        check_is_fitted(self, "models_")
        other = copy.copy(self)
        other.weights = weights
        other._choose_weights()
        return other

    def _stacking(self, models, y, val_predictions, y_val) -> np.ndarray:
        out_of_fold = np.stack([m.out_of_fold_ for m in models], axis=-1)       # (n, targets, models)
        if self.per_target:
            weights = np.column_stack([stacking_weights(out_of_fold[:, k], y[:, k]) for k in range(y.shape[1])])
        else:  # one weight vector for all targets, each target in its own spread's units
            spread = np.where(y.std(axis=0) > 0, y.std(axis=0), 1.0)
            stacked = (out_of_fold / spread[None, :, None]).reshape(-1, len(models))
            weights = np.repeat(stacking_weights(stacked, (y / spread).ravel())[:, None], y.shape[1], axis=1)
        if len(y_val) < 2:
            return weights
        # The guard, on validation: per target, or for the shared vector on the mean over targets.
        blend = np.einsum("mt,mnt->nt", weights, val_predictions)
        blend_r2 = np.array([r2_score(y_val[:, k], blend[:, k]) for k in range(y.shape[1])])
        if self.per_target:
            for k in range(y.shape[1]):
                best = int(np.nanargmax(self.val_r2_[:, k]))
                if blend_r2[k] < self.val_r2_[best, k]:
                    weights[:, k] = np.eye(len(models))[best]
                    self.stacking_fallback_targets_.append(k)
        else:
            mean_r2 = np.nanmean(self.val_r2_, axis=1)
            best = int(np.nanargmax(mean_r2))
            if blend_r2.mean() < mean_r2[best]:
                weights[:] = np.eye(len(models))[best][:, None]
                self.stacking_fallback_targets_ = list(range(y.shape[1]))
        return weights

    @property
    def names_(self) -> list[str]:
        return list(self.models_)

    def selected_(self) -> str:
        """The candidate with the largest weight summed over targets."""
        return self.names_[int(np.argmax(self.weights_.sum(axis=1)))]

    def _candidate_predictions(self, X):
        check_is_fitted(self, "models_")
        X = validate_data(self, X, reset=False, dtype=np.float64)
        n = len(X)
        means, model_variances = [], []
        for model in self.models_.values():
            if hasattr(model, "predict_components"):
                mean, model_variance, _ = model.predict_components(X)
            else:
                mean = model.predict(X).reshape(n, -1)
                model_variance = np.zeros_like(mean)
            means.append(mean)
            model_variances.append(model_variance)
        return np.stack(means), np.stack(model_variances)

    def predict(self, X):
        means, _ = self._candidate_predictions(X)
        mean = (self.weights_[:, None, :] * means).sum(axis=0)
        return mean[:, 0] if self.single_output_ else mean

    def predict_std(self, X):
        means, model_variances = self._candidate_predictions(X)
        w = self.weights_[:, None, :]
        mean = (w * means).sum(axis=0)
        model_variance = (w * (model_variances + (means - mean) ** 2)).sum(axis=0)
        return mean, np.sqrt(model_variance + self.data_variance_)

    def importances(self):
        """(name, importances) of the highest-weight candidate that has them (trees), or None."""
        order = np.argsort(-self.weights_.sum(axis=1))
        for index in order:
            model = list(self.models_.values())[index]
            given = model.importances() if capabilities(model).importances else None
            if given is not None:
                return self.names_[index], given[1]
        return None

    @property
    def n_parameters_(self) -> int:
        return sum(getattr(m, "n_parameters_", 0) for m in self.models_.values())
