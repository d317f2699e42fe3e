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
"""
import time

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin, clone
from sklearn.metrics import r2_score

from data.errors import InputError
from models.uncertainty import IntervalMixin

MODES = ("weighted", "argmax")


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
    weights = np.divide(positive, total, out=np.full_like(positive, 1.0 / len(scores)), where=total > 0)
    return weights, fallback


class ValidationWeightedBlend(IntervalMixin, BaseEstimator, RegressorMixin):
    def __init__(self, candidates=None, mode="weighted", per_target=True):
        self.candidates = candidates
        self.mode = mode
        self.per_target = per_target

    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
        if not self.candidates:
            raise InputError("model.candidates is empty: name at least one candidate model")
        if X_val is None or y_val is None:
            raise InputError("validation-guided weighting needs a validation split")
        y2 = np.asarray(y, dtype=np.float64).reshape(len(y), -1)
        y_val2 = np.asarray(y_val, dtype=np.float64).reshape(len(y_val), -1)
        self.models_, self.fit_time_s_, scores, val_residual = {}, {}, [], []
        for name, estimator in self.candidates.items():
            start = time.perf_counter()
            model = clone(estimator).fit(X, y, X_val, y_val, epoch_callback=epoch_callback, groups=groups)
            self.fit_time_s_[name] = time.perf_counter() - start
            epoch_callback = None  # curves in TensorBoard come from the first net only
            predicted = model.predict(X_val).reshape(y_val2.shape)
            scores.append([r2_score(y_val2[:, k], predicted[:, k]) if len(y_val2) > 1 else np.nan
                           for k in range(y_val2.shape[1])])
            val_residual.append(((y_val2 - predicted) ** 2).mean(axis=0))
            self.models_[name] = model
        self.val_r2_ = np.asarray(scores)
        ranking = self.val_r2_ if self.per_target else np.repeat(
            np.nanmean(self.val_r2_, axis=1, keepdims=True), self.val_r2_.shape[1], axis=1)
        self.weights_, self.fallback_targets_ = validation_weights(ranking, self.mode)
        self.val_residual_ = np.asarray(val_residual)
        models = list(self.models_.values())
        if all(hasattr(m, "out_of_fold_") for m in models):
            blended = sum(self.weights_[i] * m.out_of_fold_ for i, m in enumerate(models))
            self.data_variance_ = ((y2 - blended) ** 2).mean(axis=0)
        else:
            self.data_variance_ = (self.weights_ * self.val_residual_).sum(axis=0)
        self.n_features_in_ = np.asarray(X).shape[1]
        return self

    @property
    def names_(self) -> list[str]:
        return list(self.models_)

    def selected_(self) -> str:
        """The candidate with the largest weight summed over targets."""
        return self.names_[int(np.argmax(self.weights_.sum(axis=1)))]

    def _candidate_predictions(self, X):
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
        return (self.weights_[:, None, :] * means).sum(axis=0)

    def predict_std(self, X):
        means, model_variances = self._candidate_predictions(X)
        w = self.weights_[:, None, :]
        mean = (w * means).sum(axis=0)
        model_variance = (w * (model_variances + (means - mean) ** 2)).sum(axis=0)
        return mean, np.sqrt(model_variance + self.data_variance_)

    def selected_tree_importances(self):
        """(name, importances) of the highest-weight candidate that has them (trees), or None."""
        order = np.argsort(-self.weights_.sum(axis=1))
        for index in order:
            model = list(self.models_.values())[index]
            if hasattr(model, "feature_importances"):
                values = model.feature_importances()
                if values is not None:
                    return self.names_[index], values
        return None

    @property
    def n_parameters_(self) -> int:
        return sum(getattr(m, "n_parameters_", 0) for m in self.models_.values())
