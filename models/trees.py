"""Tree baselines behind the estimator contract: random forest, extra trees, decision tree.

The seed trains one forest per output (400 trees, depth 14, sqrt features); `per_output=False`
fits one multi-output forest instead, which is about 4x cheaper to predict with. One forest for
several targets adds their squared errors in every split, so it is grown on standardised
targets: on raw targets a pressure in pascals (sd ~7e4) would choose every split over
millimetres, and R² of x would depend on the unit pressure is given in.
"""
import numpy as np
from sklearn.multioutput import MultiOutputRegressor
from sklearn.utils.validation import check_is_fitted, validate_data

from common.errors import InputError
from common.standardise import mean_and_scale
from models.capabilities import declare
from models.classic_classifiers import TableClassifier
from models.estimator_base import TouchstoneRegressor
from models.forest_kinds import TREE_KINDS, forest
from models.storable import storable

KINDS = TREE_KINDS
storable(MultiOutputRegressor)   # per_output: one forest per target


class TreeRegressor(TouchstoneRegressor):
    def __init__(self, kind="extra_trees", n_estimators=400, max_depth=14, max_features: str | float | None = "sqrt",
                 min_samples_leaf=1, per_output=False, n_jobs=None, seed=0):
        self.kind = kind
        self.n_estimators = n_estimators
        self.max_depth = max_depth
        self.max_features = max_features
        self.min_samples_leaf = min_samples_leaf
        self.per_output = per_output
        self.n_jobs = n_jobs
        self.seed = seed

    def _base(self):
        base = forest(self.kind, False, self.n_estimators, self.max_depth, self.max_features, self.min_samples_leaf,
                      self.n_jobs, self.seed)
        if base is None:
            raise InputError(f"model.kind must be one of {', '.join(KINDS)}, got '{self.kind}'")
        return base

    def __sklearn_tags__(self):
        tags = declare(super().__sklearn_tags__(), importances=True, has_classifier=True, size="n_nodes")
        tags.target_tags.multi_output = True
        return tags

    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
        X, y = validate_data(self, X, y, multi_output=True, y_numeric=True, dtype=np.float32)
        if y.ndim == 2 and y.shape[1] == 1:
            y = y[:, 0]  # scikit-learn wants a single target as a vector
        base = self._base()
        self.estimator_ = MultiOutputRegressor(base) if self.per_output and y.ndim == 2 else base
        if y.ndim == 2 and not self.per_output:
            self._fit_in_units(X, y)
        else:
            self.estimator_.fit(X, y)
        # Predict on one thread: parallel forests add their trees' outputs in the order threads
        # finish, so the same run would differ in the last bit (the eager prediction of a big
        # forest gets slower; the exported ONNX model does not). Fitting stays parallel (each
        # tree is seeded).
        # MultiOutputRegressor's fitted forests are clones made before this line, so each is set.
        for model in (self.estimator_, *self._forests()):
            model.set_params(**{key: 1 for key in model.get_params() if key.endswith("n_jobs")})
        return self

    def _fit_in_units(self, X, y):
        """Grow the trees on standardised targets, then map every node's value back: a regression
        node holds the mean of its rows' targets, so the fitted model predicts in units, and
        predict, the ONNX graph and the saved state need nothing extra. Centring as well as
        scaling because scikit-learn's squared-error criterion subtracts two large sums, which
        loses digits on uncentred targets."""
        self.target_mean_, self.target_scale_ = mean_and_scale(y)
        self.estimator_.fit(X, (y - self.target_mean_) / self.target_scale_)
        for tree in getattr(self.estimator_, "estimators_", [self.estimator_]):
            values = tree.tree_.value[:, :, 0]
            values *= self.target_scale_
            values += self.target_mean_

    def predict(self, X):
        check_is_fitted(self, "estimator_")
        return self.estimator_.predict(validate_data(self, X, reset=False, dtype=np.float32))

    def _forests(self) -> list:
        """The fitted forests (or tree): one per target with per_output, else the one."""
        return self.estimator_.estimators_ if isinstance(self.estimator_, MultiOutputRegressor) else [self.estimator_]

    def feature_importances(self):
        """Impurity importances, averaged over the per-output forests when there are several."""
        return np.mean([m.feature_importances_ for m in self._forests()], axis=0)

    def importances(self):
        return type(self).__name__, self.feature_importances()

    def classifier(self):
        """The classifier of this kind with these settings, for a table whose target is a class label."""
        return TableClassifier(**{k: v for k, v in self.get_params().items() if k != "per_output"})

    @property
    def n_nodes_(self) -> int:
        """Total decision nodes over every tree, the trees' analogue of a parameter count."""
        total = 0
        for model in self._forests():
            trees = getattr(model, "estimators_", [model])
            total += sum(t.tree_.node_count for t in trees)
        return total
