"""Tree baselines behind the estimator contract: random forest, extra trees, decision tree.

The seed trains one forest per output (400 trees, depth 14, sqrt features); `per_output=False`
fits one multi-output forest instead, which is about 4x cheaper to predict with.
"""
import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.ensemble import ExtraTreesRegressor, RandomForestRegressor
from sklearn.multioutput import MultiOutputRegressor
from sklearn.tree import DecisionTreeRegressor

from data.errors import InputError

KINDS = ("random_forest", "extra_trees", "decision_tree")


class TreeRegressor(BaseEstimator, RegressorMixin):
    def __init__(self, kind="extra_trees", n_estimators=400, max_depth=14, max_features="sqrt",
                 min_samples_leaf=1, per_output=False, n_jobs=-1, seed=0):
        self.kind = kind
        self.n_estimators = n_estimators
        self.max_depth = max_depth
        self.max_features = max_features
        self.min_samples_leaf = min_samples_leaf
        self.per_output = per_output
        self.n_jobs = n_jobs
        self.seed = seed

    def _base(self):
        common = dict(max_depth=self.max_depth, max_features=self.max_features,
                      min_samples_leaf=self.min_samples_leaf, random_state=self.seed)
        if self.kind == "decision_tree":
            return DecisionTreeRegressor(**common)
        if self.kind == "random_forest":
            return RandomForestRegressor(n_estimators=self.n_estimators, n_jobs=self.n_jobs, **common)
        if self.kind == "extra_trees":
            return ExtraTreesRegressor(n_estimators=self.n_estimators, n_jobs=self.n_jobs, **common)
        raise InputError(f"model.kind must be one of {', '.join(KINDS)}, got '{self.kind}'")

    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
        base = self._base()
        y = np.asarray(y)
        if y.ndim == 2 and y.shape[1] == 1:
            y = y[:, 0]  # scikit-learn wants a single target as a vector
        self.estimator_ = MultiOutputRegressor(base) if self.per_output else base
        self.estimator_.fit(X, y)
        self.n_features_in_ = self.estimator_.n_features_in_
        return self

    def predict(self, X):
        return self.estimator_.predict(X)

    def feature_importances(self):
        """Impurity importances, averaged over the per-output forests when there are several."""
        fitted = self.estimator_.estimators_ if self.per_output else [self.estimator_]
        return np.mean([m.feature_importances_ for m in fitted], axis=0)

    @property
    def n_nodes_(self) -> int:
        """Total decision nodes over every tree, the trees' analogue of a parameter count."""
        fitted = self.estimator_.estimators_ if self.per_output else [self.estimator_]
        total = 0
        for model in fitted:
            trees = getattr(model, "estimators_", [model])
            total += sum(t.tree_.node_count for t in trees)
        return total
