"""Classifiers for tables (one row per press, a categorical target), behind the estimator
contract: decision tree, random forest, extra trees, a multilayer perceptron and logistic
regression, each the scikit-learn estimator of that name on the datamodule's standardised
features (data/datamodules/regression.py).

Probabilities are calibrated by temperature scaling (Guo et al., "On calibration of modern
neural networks", ICML 2017): p = softmax(beta * log(p_raw + EPS)), beta fitted on held-out
calibration rows by maximum likelihood (the method scikit-learn's CalibratedClassifierCV calls
"temperature"; tests/runs/test_table_classification.py checks the two agree). One number, so a few
dozen rows fit it without overfitting, and it keeps every row's most probable class: the
classification report and confusion matrix are the classifier's own. The exported graph
(export/sklearn_graphs.py) applies the same three steps after the scikit-learn piece.

A model chosen for a regression table maps to its classifier when the table's target turns out
categorical (runs/classification.py: `classifier_settings`): the trees keep their settings.
"""
import logging
import warnings

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.special import log_softmax, softmax
from sklearn.exceptions import ConvergenceWarning
from sklearn.linear_model import LogisticRegression
from sklearn.neural_network import MLPClassifier
from sklearn.neural_network._stochastic_optimizers import AdamOptimizer
from sklearn.preprocessing import LabelBinarizer
from sklearn.utils.validation import check_is_fitted, validate_data

from common.errors import InputError
from models.capabilities import declare
from models.estimator_base import TouchstoneClassifier
from models.forest_kinds import TREE_KINDS, forest
from models.storable import storable

log = logging.getLogger(__name__)
KINDS = TREE_KINDS + ("mlp", "logistic_regression")
storable(LogisticRegression, MLPClassifier, AdamOptimizer, LabelBinarizer)   # what the non-tree kinds hold
EPS = 1e-12               # log(0) guard, as scikit-learn's temperature scaling adds
LOG_BETA_BOUNDS = (-10.0, 10.0)


def fit_temperature(proba: np.ndarray, y: np.ndarray) -> float:
    """The inverse temperature beta minimising the log loss of softmax(beta * log(proba + EPS))
    on rows with true class codes `y`."""
    logits = np.log(np.asarray(proba, dtype=np.float64) + EPS)
    rows = np.arange(len(y))

    def loss(log_beta):
        return -log_softmax(np.exp(log_beta) * logits, axis=1)[rows, y].mean()

    return float(np.exp(minimize_scalar(loss, bounds=LOG_BETA_BOUNDS, method="bounded",
                                        options={"xatol": 1e-10}).x))


def calibrated(proba: np.ndarray, beta: float) -> np.ndarray:
    return softmax(beta * np.log(np.asarray(proba, dtype=np.float64) + EPS), axis=1)


class TableClassifier(TouchstoneClassifier):
    """`kind` picks the scikit-learn classifier; the tree settings are the regression trees'
    (models/trees.py), `hidden_layer_sizes`/`max_iter` the MLP's, `C` logistic regression's."""

    def __init__(self, kind="extra_trees", n_estimators=400, max_depth: int | None = 14,
                 max_features: str | float | None = "sqrt", min_samples_leaf=1, hidden_layer_sizes=(64, 32),
                 max_iter=500, C=1.0, n_jobs=None, seed=0):
        self.kind = kind
        self.n_estimators = n_estimators
        self.max_depth = max_depth
        self.max_features = max_features
        self.min_samples_leaf = min_samples_leaf
        self.hidden_layer_sizes = hidden_layer_sizes
        self.max_iter = max_iter
        self.C = C
        self.n_jobs = n_jobs
        self.seed = seed

    def __sklearn_tags__(self):
        return declare(super().__sklearn_tags__(), calibrates_probabilities=True, named_by="kind", size="n_parameters")

    def _base(self):
        trees = forest(self.kind, True, self.n_estimators, self.max_depth, self.max_features, self.min_samples_leaf,
                       self.n_jobs, self.seed)
        if trees is not None:
            return trees
        if self.kind == "mlp":
            # Adam until the training loss stops improving (scikit-learn's tol), at most max_iter epochs
            return MLPClassifier(hidden_layer_sizes=tuple(self.hidden_layer_sizes), max_iter=self.max_iter,
                                 random_state=self.seed)
        if self.kind == "logistic_regression":
            return LogisticRegression(C=self.C, max_iter=self.max_iter)
        raise InputError(f"model.kind must be one of {', '.join(KINDS)}, got '{self.kind}'")

    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
        """y: class codes 0..k-1, every code present (the datamodule checks)."""
        X, y = validate_data(self, X, y, dtype=np.float32 if self.kind in TREE_KINDS else np.float64)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ConvergenceWarning)
            self.estimator_ = self._base().fit(X, y)
        if any(issubclass(w.category, ConvergenceWarning) for w in caught):  # one log line, not a warning's two
            log.warning("%s: stopped at model.max_iter=%d before the training loss settled", self.kind, self.max_iter)
        self.classes_ = self.estimator_.classes_
        if self.kind not in TREE_KINDS:   # max_iter's iterations: the epochs or solver steps taken
            self.n_iter_ = self.estimator_.n_iter_
        # one thread to predict: the forest's sum over trees then has one order (same run, same bits)
        self.estimator_.set_params(**{key: 1 for key in self.estimator_.get_params() if key.endswith("n_jobs")})
        self.temperature_beta_ = 1.0   # uncalibrated until `calibrate`
        return self

    def calibrate(self, X, y) -> "TableClassifier":
        self.temperature_beta_ = fit_temperature(self.raw_proba(X), np.asarray(y))
        return self

    def raw_proba(self, X) -> np.ndarray:
        """The scikit-learn classifier's own probabilities, before calibration."""
        check_is_fitted(self, "estimator_")
        dtype = np.float32 if self.kind in TREE_KINDS else np.float64
        return self.estimator_.predict_proba(validate_data(self, X, reset=False, dtype=dtype))

    def predict_proba(self, X) -> np.ndarray:
        return calibrated(self.raw_proba(X), self.temperature_beta_)

    def predict(self, X) -> np.ndarray:
        proba = self.predict_proba(X)   # first: unfitted, it says so (NotFittedError)
        return self.classes_[proba.argmax(axis=1)]

    def feature_importances(self):
        return getattr(self.estimator_, "feature_importances_", None)

    @property
    def n_parameters_(self) -> int:
        """Decision nodes of every tree, or the weights and biases of the MLP / logistic regression."""
        check_is_fitted(self, "estimator_")
        model = self.estimator_
        if self.kind in TREE_KINDS:
            return int(sum(t.tree_.node_count for t in getattr(model, "estimators_", [model])))
        if self.kind == "mlp":
            return int(sum(w.size for w in model.coefs_) + sum(b.size for b in model.intercepts_))
        return int(model.coef_.size + model.intercept_.size)
