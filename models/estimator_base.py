"""The base classes of Touchstone's estimators: they own the shared `fit` signature, declare the
capabilities every one of ours has (models/capabilities.py) and register the class as storable
(models/storable.py), so a new model is one class deriving from one of these.

    fit(X, y, X_val=None, y_val=None, epoch_callback=None, groups=None) -> self

X_val, y_val: validation rows (early stopping, choosing); epoch_callback(record): per-epoch
logging; groups: the group of each training row (folds and carved validation keep a group
together). A model ignores what it has no use for. A subclass declares more in
`__sklearn_tags__` with `declare(super().__sklearn_tags__(), intervals=True, ...)`.
"""
import inspect

from sklearn.base import BaseEstimator, ClassifierMixin, RegressorMixin

from models.capabilities import declare
from models.storable import storable

SHARED_FIT = ("self", "X", "y", "X_val", "y_val", "epoch_callback", "groups")


class TouchstoneEstimator(BaseEstimator):
    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        parameters = tuple(inspect.signature(cls.fit).parameters)
        if parameters != SHARED_FIT:   # said when the class is defined, not when a run reaches fit
            raise TypeError(f"{cls.__qualname__}.fit{parameters} must take the shared signature {SHARED_FIT}")
        storable(cls)

    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
        raise NotImplementedError

    def __sklearn_tags__(self):
        return declare(super().__sklearn_tags__(), shared_fit=True, storable=True)


class TouchstoneRegressor(RegressorMixin, TouchstoneEstimator):
    pass


class TouchstoneClassifier(ClassifierMixin, TouchstoneEstimator):
    pass
