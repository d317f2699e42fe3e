"""Constant columns (up to rounding) are standardised with scale 1, so the float64 model and its
float32 copy see the same inputs (a 3-channel table's kurtosis feature is -1.5 +- 1e-16)."""
import numpy as np

from models.resmlp_regressor import ResMLPRegressor
from common.standardise import mean_and_scale


def rounding_constant_column(n, rng):
    # -1.5 computed the way a feature pipeline does, with float64 rounding noise left in
    a = rng.normal(size=(n, 3))
    centred = a - a.mean(axis=1, keepdims=True)
    return ((centred ** 4).mean(axis=1) / (centred ** 2).mean(axis=1) ** 2) - 3.0


def test_rounding_noise_counts_as_constant():
    rng = np.random.default_rng(0)
    column = rounding_constant_column(200, rng)
    assert 0 < column.std() < 1e-14
    _, scale = mean_and_scale(np.column_stack([column, rng.normal(size=200) * 1e-9]))
    assert scale[0] == 1.0
    assert np.isclose(scale[1], 1e-9, rtol=0.2)     # a small but real spread is kept


def test_resmlp_prediction_does_not_depend_on_rounding_of_a_constant_feature():
    rng = np.random.default_rng(1)
    X = np.column_stack([rng.normal(size=(120, 2)), rounding_constant_column(120, rng)])
    y = X[:, :1] * 2.0
    model = ResMLPRegressor(widths=(16,), dropouts=(0.0,), noise_std=0.0, max_epochs=3, seed=0,
                            progress=False).fit(X, y)
    as_float32 = X.astype(np.float32).astype(np.float64)
    np.testing.assert_allclose(model.predict(X), model.predict(as_float32), atol=1e-4)
