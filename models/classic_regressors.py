"""Seed 001's force-from-capacitance models behind the estimator contract: linear regression,
support-vector regression with a linear kernel, and Gaussian-process regression (the fourth,
the decision tree, is models/trees.py with kind=decision_tree).

Seed 001 (sec. 2.6, 3.5) fits each of them from RMC to force; here they take the datamodule's
standardised features (raw RMC per cell for the capacitive scene) and every target in units.
Targets are standardised inside `fit` (their mean and spread from the training rows) so the
SVR's epsilon tube and the GP's noise level mean the same for millimetres and newtons; the
prediction is turned back into units, and the ONNX graph (export/sklearn_graphs.py) does the
same affine step after the scikit-learn pieces.

- linear_regression: ordinary least squares, one multi-output model.
- ridge: least squares with an L2 penalty on the coefficients, the penalty chosen among
  `ridge_alphas` by validation R^2 (the validation rows when given, else a split carved from the
  training rows, grouped when groups are given), then refitted on all training rows. Ordinary
  least squares on the default rubber12 scene's 74 heavy-tailed physics features extrapolates
  wildly onto press groups it has not seen (validation R^2 from -0.80 to +0.75 between seeds);
  shrinking the coefficients bounds that (docs/pipeline.md, "The linear family across splits").
  Solved as least squares on the rows augmented with +-sqrt(alpha) I (targets 0), which on
  standardised features and targets is ridge with penalty 2 alpha and leaves a LinearRegression:
  the same ONNX graph and fitted-state file as ordinary least squares.
- svr: epsilon-SVR, kernel "linear" (libsvm, as the paper's "SVM with a linear kernel"), one
  per target (SVR is single-output).
- gaussian_process: a GP with kernel C1 * DotProduct + C2 * RBF + White (the dot product
  carries the sensor's near-linear response, the RBF what is left, the white kernel the
  noise), hyper-parameters by maximum marginal likelihood. Exact GP training costs O(n^3)
  time and its gradient O(n^2 k) memory, so at most `max_train_samples` rows (a seeded random
  subset, reported as `n_train_used_`) are used.
"""
import numpy as np
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel, DotProduct, Product, Sum, WhiteKernel
from sklearn.linear_model import LinearRegression
from sklearn.metrics import r2_score
from sklearn.svm import SVR
from sklearn.utils.validation import check_is_fitted, validate_data

from common.errors import InputError
from data.splits.indices import carve_validation
from models.capabilities import declare
from models.estimator_base import TouchstoneRegressor
from models.storable import storable

KINDS = ("linear_regression", "ridge", "svr", "gaussian_process")
RIDGE_ALPHAS = (0.01, 0.1, 1.0, 10.0, 100.0, 1000.0)
# What the kinds hold: the fitted library estimators and the GP's kernel terms
storable(LinearRegression, SVR, GaussianProcessRegressor, ConstantKernel, DotProduct, Product, RBF, Sum, WhiteKernel)


def ridge(X, z, alpha: float) -> LinearRegression:
    """Least squares on the rows augmented with +-sqrt(alpha) I (targets 0): the ridge solution
    (X'X + 2 alpha I) w = X'z for centred X and z, as a LinearRegression."""
    eye = np.sqrt(alpha) * np.eye(X.shape[1])
    zeros = np.zeros((2 * X.shape[1], z.shape[1]))
    return LinearRegression().fit(np.vstack([X, eye, -eye]), np.vstack([z, zeros]))


class ClassicRegressor(TouchstoneRegressor):
    def __init__(self, kind="linear_regression", svr_c=1.0, svr_epsilon=0.01, gp_restarts=0,
                 max_train_samples=1000, ridge_alphas=RIDGE_ALPHAS, val_fraction=0.15, seed=0):
        self.kind = kind
        self.ridge_alphas = ridge_alphas
        self.val_fraction = val_fraction
        self.svr_c = svr_c
        self.svr_epsilon = svr_epsilon
        self.gp_restarts = gp_restarts
        self.max_train_samples = max_train_samples
        self.seed = seed

    def __sklearn_tags__(self):
        tags = declare(super().__sklearn_tags__(), size="n_parameters")
        tags.target_tags.multi_output = True
        return tags

    def _check_params(self):
        if self.kind not in KINDS:
            raise InputError(f"model.kind must be one of {', '.join(KINDS)}, got '{self.kind}'")
        if not (self.svr_c > 0 and self.svr_epsilon >= 0):
            raise InputError(f"model.svr_c must be > 0 and model.svr_epsilon >= 0, got {self.svr_c}, {self.svr_epsilon}")
        if self.max_train_samples is not None and (not isinstance(self.max_train_samples, (int, np.integer))
                                                   or self.max_train_samples < 2):
            raise InputError(f"model.max_train_samples must be an integer >= 2 or null, got {self.max_train_samples!r}")

    def _gaussian_process(self, n_features):
        # DotProduct's sigma_0 is fixed: the targets are centred, and a free offset only drifts
        # to its bound (a ConvergenceWarning per fit) without changing the fit
        kernel = (ConstantKernel(1.0, (1e-3, 1e3)) * DotProduct(1.0, "fixed")
                  + ConstantKernel(0.1, (1e-4, 1e2)) * RBF(np.sqrt(n_features), (1e-2, 1e3))
                  + WhiteKernel(1e-2, (1e-6, 1.0)))
        return GaussianProcessRegressor(kernel, n_restarts_optimizer=self.gp_restarts, random_state=self.seed)

    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
        self._check_params()
        X, y = validate_data(self, X, y, multi_output=True, y_numeric=True, dtype=np.float64)
        self.single_target_ = y.ndim == 1
        y = y.reshape(len(y), -1)
        self.target_mean_ = y.mean(axis=0)
        spread = y.std(axis=0)
        self.target_scale_ = np.where(spread > 0, spread, 1.0)
        z = (y - self.target_mean_) / self.target_scale_
        if self.kind == "gaussian_process" and self.max_train_samples and len(X) > self.max_train_samples:
            keep = np.sort(np.random.default_rng(self.seed).choice(len(X), self.max_train_samples, replace=False))
            X, z = X[keep], z[keep]
        self.n_train_used_ = len(X)
        if self.kind == "linear_regression":
            self.estimators_ = [LinearRegression().fit(X, z)]
        elif self.kind == "ridge":
            self.alpha_, self.alpha_scores_ = self._choose_alpha(X, z, X_val, y_val, groups)
            self.estimators_ = [ridge(X, z, self.alpha_)]
        elif self.kind == "svr":
            self.estimators_ = [SVR(kernel="linear", C=self.svr_c, epsilon=self.svr_epsilon).fit(X, z[:, k])
                                for k in range(z.shape[1])]
        else:
            self.estimators_ = [self._gaussian_process(X.shape[1]).fit(X, z)]
        return self

    def _choose_alpha(self, X, z, X_val, y_val, groups):
        """(alpha, mean validation R^2 of each of ridge_alphas) among ridge_alphas."""
        if not self.ridge_alphas or any(not (a > 0) for a in self.ridge_alphas):
            raise InputError(f"model.ridge_alphas must be positive numbers, got {self.ridge_alphas!r}")
        if X_val is not None and y_val is not None:
            X_fit, z_fit = X, z
            X_val = validate_data(self, X_val, reset=False, dtype=np.float64)
            z_val = (np.asarray(y_val, dtype=np.float64).reshape(len(X_val), -1) - self.target_mean_) / self.target_scale_
        else:
            fit_rows, val_rows = carve_validation(len(X), self.val_fraction, self.seed, groups)
            X_fit, z_fit, X_val, z_val = X[fit_rows], z[fit_rows], X[val_rows], z[val_rows]
        alphas = np.asarray(self.ridge_alphas, dtype=np.float64)
        scores = np.array([np.mean([r2_score(z_val[:, k], p[:, k]) for k in range(z.shape[1])])
                           for a in alphas for p in [ridge(X_fit, z_fit, a).predict(X_val).reshape(z_val.shape)]])
        best = max(range(len(alphas)), key=lambda i: (scores[i], alphas[i]))   # ties: the stronger penalty
        return float(alphas[best]), scores

    def predict_standardised(self, X) -> np.ndarray:
        """[n, n_targets] predictions before the targets' de-standardisation."""
        check_is_fitted(self, "estimators_")
        X = validate_data(self, X, reset=False, dtype=np.float64)
        parts = [np.asarray(m.predict(X)).reshape(len(X), -1) for m in self.estimators_]
        return np.hstack(parts)

    def predict(self, X):
        y = self.predict_standardised(X) * self.target_scale_ + self.target_mean_
        return y[:, 0] if self.single_target_ else y

    @property
    def n_parameters_(self) -> int:
        """Numbers a prediction needs: coefficients (linear regression, and the linear-kernel
        SVR's primal weights), or the training inputs and their weights (GP)."""
        check_is_fitted(self, "estimators_")
        total = 0
        for m in self.estimators_:
            if isinstance(m, LinearRegression):
                total += m.coef_.size + np.size(m.intercept_)
            elif isinstance(m, SVR):   # linear kernel: the primal weights w = sum_i alpha_i sv_i and b
                total += m.coef_.size + 1
            else:
                total += m.X_train_.size + m.alpha_.size
        return int(total)
