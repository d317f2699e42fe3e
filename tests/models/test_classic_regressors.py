"""ClassicRegressor(kind="ridge"): least squares with an L2 penalty chosen on validation, stored
as a LinearRegression (the same ONNX graph and fitted-state file as ordinary least squares)."""
import numpy as np
import pytest
from sklearn.linear_model import LinearRegression, Ridge

from common.errors import InputError
from models.classic_regressors import ClassicRegressor, ridge


def test_the_augmented_least_squares_is_ridge_on_centred_data():
    rng = np.random.default_rng(0)
    X = rng.standard_normal((50, 6))
    X -= X.mean(axis=0)
    z = X @ rng.standard_normal((6, 2)) + rng.standard_normal((50, 2))
    z -= z.mean(axis=0)
    fitted = ridge(X, z, 3.0)
    assert isinstance(fitted, LinearRegression)
    np.testing.assert_allclose(fitted.coef_, Ridge(alpha=6.0).fit(X, z).coef_, atol=1e-10)


def test_the_penalty_is_chosen_on_validation_and_shrinks_what_extrapolates():
    """Many noise features and few rows: least squares overfits; a stronger penalty wins on validation."""
    rng = np.random.default_rng(1)
    X = rng.standard_normal((60, 40))
    y = X[:, 0] + 0.5 * rng.standard_normal(60)
    X_val = rng.standard_normal((60, 40))
    y_val = X_val[:, 0] + 0.5 * rng.standard_normal(60)
    model = ClassicRegressor(kind="ridge").fit(X, y, X_val, y_val)
    assert model.alpha_ == model.ridge_alphas[int(np.argmax(model.alpha_scores_))] and model.alpha_ >= 1.0
    ols = ClassicRegressor(kind="linear_regression").fit(X, y)
    r2 = lambda m: 1 - np.mean((m.predict(X_val) - y_val) ** 2) / np.var(y_val)  # noqa: E731
    assert r2(model) > r2(ols)
    carved = ClassicRegressor(kind="ridge", seed=2).fit(X, y, groups=np.arange(60) // 3)   # no validation given
    assert carved.alpha_ in carved.ridge_alphas and len(carved.alpha_scores_) == len(carved.ridge_alphas)
    with pytest.raises(InputError, match="ridge_alphas must be positive"):
        ClassicRegressor(kind="ridge", ridge_alphas=[0.0]).fit(X, y, X_val, y_val)
