"""K-fold blending (seed eq. 17): K copies of a model, each trained on K - 1 folds of the
training data, averaged at prediction time.

Works for any estimator of the contract. The fold models' spread gives the model uncertainty
sigma_model (eq. 21); the out-of-fold residuals give the data noise sigma_data (eq. 22, one
variance per target); the total is sigma_total = sqrt(sigma_model^2 + sigma_data^2) (eq. 23-24).
Classifiers average probabilities.

The held-out fold is never shown to its fold model: a net carves its early-stopping rows from
its own K - 1 folds (grouped when groups are given), so the out-of-fold predictions that feed
sigma_data and the stacking weights come from rows the model neither trained nor stopped on.

`resample="seeds"` makes the same K members a seed ensemble instead: each is trained on every
training row with its own seed (the comparison docs/pipeline.md reports: K-fold blending against
one model on all rows and against a seed ensemble). It has no out-of-fold predictions; sigma_data
then comes from the validation rows when given, else from the training residuals.
"""
import logging
import time

import numpy as np
from sklearn.base import clone
from sklearn.utils.metaestimators import available_if
from sklearn.utils.validation import check_is_fitted, validate_data

from common.errors import InputError
from common.progress import progress
from data.splits.indices import kfold_indices
from models.capabilities import capabilities, declare
from models.epoch_callback import member_callback
from models.estimator_base import TouchstoneRegressor
from models.uncertainty import IntervalMixin

log = logging.getLogger(__name__)
RESAMPLE = ("kfold", "seeds")


class KFoldBlend(IntervalMixin, TouchstoneRegressor):
    def __init__(self, estimator=None, n_folds=5, seed=0, progress=True, resample="kfold"):
        self.estimator = estimator
        self.n_folds = n_folds
        self.seed = seed
        self.progress = progress
        self.resample = resample

    def __sklearn_tags__(self):
        members = capabilities(self.estimator) if self.estimator is not None else None
        tags = declare(super().__sklearn_tags__(), intervals=True, fold_costs=True, size="n_parameters",
                       importances=bool(members and members.importances))
        tags.target_tags.multi_output = True
        tags.target_tags.single_output = True
        return tags

    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
        """X_val and y_val are not used by K-fold members (the folds validate); a seed ensemble
        takes its data variance from them."""
        X, y = validate_data(self, X, y, multi_output=True, y_numeric=True, dtype=np.float64)
        if self.estimator is None:
            raise ValueError("KFoldBlend needs an estimator to blend")
        if self.resample not in RESAMPLE:
            raise InputError(f"model.resample must be one of {', '.join(RESAMPLE)}, got '{self.resample}'")
        y2 = y.reshape(len(y), -1)
        self.models_, self.fold_fit_time_s_, self.fold_fit_cpu_time_s_ = [], [], []
        out_of_fold = np.zeros_like(y2)
        if self.resample == "seeds":
            if not (isinstance(self.n_folds, (int, np.integer)) and self.n_folds >= 1):
                raise InputError(f"a seed ensemble needs n_folds >= 1 members, got {self.n_folds!r}")
            everything = np.arange(len(X))
            folds, self.fold_warning_ = [(everything, everything[:0])] * self.n_folds, None
        else:
            folds, self.fold_warning_ = kfold_indices(len(X), self.n_folds, self.seed, groups)
        if self.fold_warning_:
            log.warning(self.fold_warning_)
        desc, unit = ("seed ensemble", "members") if self.resample == "seeds" else ("k-fold", "folds")
        for k, (fit_rows, held_rows) in enumerate(progress(folds, desc=desc, unit=unit, enabled=self.progress)):
            model = clone(self.estimator)
            if "seed" in model.get_params():
                model.set_params(seed=self.seed + k)
            start, cpu_start = time.perf_counter(), time.process_time()
            model.fit(X[fit_rows], y[fit_rows], epoch_callback=member_callback(epoch_callback, f"fold{k}"),
                      groups=None if groups is None else np.asarray(groups)[fit_rows])
            self.fold_fit_time_s_.append(time.perf_counter() - start)
            self.fold_fit_cpu_time_s_.append(time.process_time() - cpu_start)
            if hasattr(model, "predict_proba"):
                out_of_fold = None
            elif len(held_rows):
                out_of_fold[held_rows] = model.predict(X[held_rows]).reshape(len(held_rows), -1)
            self.models_.append(model)
        self.single_output_ = y.ndim == 1
        if out_of_fold is not None and self.resample == "kfold":
            self.out_of_fold_ = out_of_fold
            self.data_variance_ = ((y2 - out_of_fold) ** 2).mean(axis=0)
        elif out_of_fold is not None:  # a seed ensemble: residuals of rows it did not train on when there are any
            rows_X, rows_y = (X, y2) if X_val is None or y_val is None else (
                validate_data(self, X_val, reset=False, dtype=np.float64), np.asarray(y_val).reshape(len(y_val), -1))
            self.data_variance_ = ((rows_y - self._fold_predictions(rows_X).mean(axis=0)) ** 2).mean(axis=0)
        return self

    def _fold_predictions(self, X) -> np.ndarray:
        check_is_fitted(self, "models_")
        X = validate_data(self, X, reset=False, dtype=np.float64)
        return np.stack([m.predict(X).reshape(len(X), -1) for m in self.models_])

    def predict(self, X):
        mean = self._fold_predictions(X).mean(axis=0)
        return mean[:, 0] if self.single_output_ else mean

    @available_if(lambda self: hasattr(self.estimator, "predict_proba"))
    def predict_proba(self, X):
        check_is_fitted(self, "models_")
        return np.mean([m.predict_proba(X) for m in self.models_], axis=0)

    def predict_components(self, X):
        """(mean, model variance, data variance) per row and target (eq. 21-22)."""
        folds = self._fold_predictions(X)
        model_variance = folds.var(axis=0, ddof=1)
        return folds.mean(axis=0), model_variance, np.broadcast_to(self.data_variance_, model_variance.shape)

    def predict_std(self, X):
        """(mean, sigma_total) per row and target (eq. 23-24)."""
        mean, model_variance, data_variance = self.predict_components(X)
        return mean, np.sqrt(model_variance + data_variance)

    def importances(self):
        """(its class name, mean impurity importances over the fold models), or None (no trees)."""
        values = [m.importances()[1] for m in self.models_ if capabilities(m).importances]
        values = [v for v in values if v is not None]
        return (type(self).__name__, np.mean(values, axis=0)) if values else None

    @property
    def n_parameters_(self) -> int:
        return sum(getattr(m, "n_parameters_", 0) for m in self.models_)
