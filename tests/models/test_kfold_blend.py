"""KFoldBlend(resample="seeds"): K members on every training row, one seed each (the comparison
bench/blend_resampling.py and docs/pipeline.md make against K-fold blending)."""
import numpy as np
import pytest

from common.errors import InputError
from models.kfold_blend import KFoldBlend
from models.trees import TreeRegressor


def test_a_seed_ensemble_trains_every_member_on_all_rows_with_its_own_seed():
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, (120, 3))
    y = np.column_stack([X[:, 0] + 0.1 * rng.standard_normal(120), X[:, 1] * X[:, 2]])
    trees = TreeRegressor(kind="extra_trees", n_estimators=5, max_depth=None, seed=0)
    ensemble = KFoldBlend(trees, n_folds=3, seed=7, progress=False, resample="seeds").fit(X[:100], y[:100],
                                                                                           X[100:], y[100:])
    assert [m.seed for m in ensemble.models_] == [7, 8, 9]
    alone = [TreeRegressor(kind="extra_trees", n_estimators=5, max_depth=None, seed=s).fit(X[:100], y[:100])
             for s in (7, 8, 9)]
    np.testing.assert_allclose(ensemble.predict(X[100:]), np.mean([m.predict(X[100:]) for m in alone], axis=0))
    assert not hasattr(ensemble, "out_of_fold_")   # no held-out rows: stacking cannot use it
    residual = ((y[100:] - ensemble.predict(X[100:])) ** 2).mean(axis=0)
    np.testing.assert_allclose(ensemble.data_variance_, residual)   # sigma_data from the validation rows
    with pytest.raises(InputError, match="model.resample must be one of kfold, seeds"):
        KFoldBlend(trees, resample="bootstrap").fit(X, y)
