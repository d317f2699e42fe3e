"""Ridge regression onto +-1 class indicators with the penalty chosen by efficient leave-one-out,
as scikit-learn's RidgeClassifierCV does (the ROCKET papers' head for small training sets).

With an unpenalised intercept the fitted values are a linear smoother of the targets,
y_hat = H y with H = 11'/n + Xc (Xc'Xc + alpha I)^-1 Xc' (Xc: the centred features), and the
leave-one-out residual of sample i is exactly (y_i - y_hat_i) / (1 - H_ii). One eigendecomposition
of the centred Gram matrix Xc Xc' = Q diag(lam) Q' gives H and the coefficients for every alpha of
the grid: H = 11'/n + Q diag(lam / (lam + alpha)) Q'. The alpha kept is the one with the least
summed squared leave-one-out residual over all class columns (ties: the smaller alpha). Costs
n^2 x features for the Gram matrix and n^3 for its eigendecomposition, so it is for training sets
of hundreds to a few thousand samples; larger ones take the logistic head.
"""
from dataclasses import dataclass

import numpy as np

ALPHAS = np.logspace(-3, 3, 10)   # the grid the ROCKET papers' code passes to RidgeClassifierCV


def class_indicators(y: np.ndarray, n_classes: int) -> np.ndarray:
    """+1 in a sample's class column, -1 elsewhere: [n, n_classes] (two columns for two classes too)."""
    targets = -np.ones((len(y), n_classes))
    targets[np.arange(len(y)), y] = 1.0
    return targets


@dataclass
class RidgeFit:
    coef: np.ndarray          # [n_features, n_targets]
    intercept: np.ndarray     # [n_targets]
    alpha: float
    loo_predictions: np.ndarray   # [n, n_targets]: each sample predicted by the fit without it (chosen alpha)
    loo_errors: np.ndarray        # [n_alphas]: summed squared leave-one-out residuals


def ridge_loo(X: np.ndarray, Y: np.ndarray, alphas=ALPHAS) -> RidgeFit:
    X, Y = np.asarray(X, dtype=np.float64), np.asarray(Y, dtype=np.float64)
    n = len(X)
    x_mean, y_mean = X.mean(axis=0), Y.mean(axis=0)
    Xc, Yc = X - x_mean, Y - y_mean
    eigenvalues, Q = np.linalg.eigh(Xc @ Xc.T)
    eigenvalues = np.clip(eigenvalues, 0.0, None)    # rounding noise below zero on a singular Gram matrix
    QtY = Q.T @ Yc
    errors, fits = [], []
    for alpha in alphas:
        shrink = eigenvalues / (eigenvalues + alpha)
        fitted = y_mean + Q @ (shrink[:, None] * QtY)
        leverage = 1.0 / n + np.einsum("ij,j,ij->i", Q, shrink, Q)
        loo = Y - (Y - fitted) / (1.0 - leverage)[:, None]
        errors.append(float(((Y - loo) ** 2).sum()))
        fits.append(loo)
    best = int(np.argmin(errors))
    alpha = float(alphas[best])
    dual = Q @ (QtY / (eigenvalues + alpha)[:, None])   # (Xc Xc' + alpha I)^-1 Yc
    coef = Xc.T @ dual
    return RidgeFit(coef, y_mean - x_mean @ coef, alpha, fits[best], np.asarray(errors))
