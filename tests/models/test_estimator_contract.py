"""The estimator contract, shared by the net and the trees."""
import numpy as np
import pytest
from sklearn.base import clone

from common.errors import InputError
from models.nets.resmlp import ResMLP
from models.resmlp_regressor import ResMLPRegressor
from models.trees import TreeRegressor


def toy(n=160, seed=0):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, 6))
    y = np.column_stack([X[:, 0] * 10 + 50, X[:, 1] - X[:, 2]])
    return X, y


MODELS = [
    ResMLPRegressor(max_epochs=6, progress=False, batch_size=16),
    TreeRegressor(kind="random_forest", n_estimators=8, per_output=True),
    TreeRegressor(kind="extra_trees", n_estimators=8),
    TreeRegressor(kind="decision_tree", max_features=None),
]


@pytest.mark.parametrize("model", MODELS, ids=lambda m: getattr(m, "kind", "resmlp"))
def test_contract_fit_returns_self_learned_state_ends_in_underscore(model):
    X, y = toy()
    fresh = clone(model)
    assert not [k for k in vars(fresh) if k.endswith("_")]  # nothing learned before fit
    assert fresh.fit(X, y) is fresh
    learned = [k for k in vars(fresh) if k.endswith("_")]
    assert learned and fresh.n_features_in_ == 6
    prediction = fresh.predict(X)
    assert prediction.shape == y.shape and np.isfinite(prediction).all()
    assert set(fresh.get_params()) == set(model.get_params())


def test_resmlp_is_the_seeds_network():
    net = ResMLP(74, 4)
    widths = [b.skip.out_features for b in net.body[1:]]
    dropouts = [b.main[3].p for b in net.body[1:]]
    assert widths == [256, 128, 96, 64] and dropouts == [0.40, 0.35, 0.30, 0.25]
    assert net.body[0].std == 0.02 and net.head.out_features == 4
    kinds = [type(m).__name__ for m in net.body[1].main]
    assert kinds == ["Linear", "ReLU", "BatchNorm1d", "Dropout", "Linear", "ReLU", "BatchNorm1d"]


def test_resmlp_is_deterministic_under_the_seed_and_learns():
    X, y = toy(300)
    a = ResMLPRegressor(max_epochs=40, progress=False, seed=4).fit(X[:240], y[:240], X[240:], y[240:])
    b = ResMLPRegressor(max_epochs=40, progress=False, seed=4).fit(X[:240], y[:240], X[240:], y[240:])
    np.testing.assert_array_equal(a.predict(X[240:]), b.predict(X[240:]))
    assert [h["val_loss"] for h in a.history_] == [h["val_loss"] for h in b.history_]
    assert a.score(X[240:], y[240:]) > 0.8  # R^2 in units: targets were standardised and restored
    assert a.history_[-1]["train_loss"] < a.history_[0]["train_loss"]


def test_resmlp_stops_early_and_restores_the_best_weights():
    X, y = toy(200)
    model = ResMLPRegressor(max_epochs=200, early_stopping_patience=3, lr=0.05, progress=False)
    model.fit(X[:150], y[:150], X[150:], y[150:])
    assert model.n_epochs_ < 200
    best = min(h["val_loss"] for h in model.history_)
    assert model.best_val_loss_ == best
    scaled = (y[150:] - model.target_mean_) / model.target_scale_
    restored = np.mean(((model.predict(X[150:]) - model.target_mean_) / model.target_scale_ - scaled) ** 2)
    assert restored == pytest.approx(best, rel=1e-4)


def test_resmlp_survives_a_last_batch_of_one_and_reports_divergence():
    X, y = toy(33)  # 33 rows, batch 32: the last batch has a single row
    ResMLPRegressor(max_epochs=2, batch_size=32, progress=False).fit(X, y, X[:5], y[:5])
    with pytest.raises(InputError, match="diverged at epoch 1"):
        ResMLPRegressor(max_epochs=2, lr=1e12, progress=False).fit(X, y, X[:5], y[:5])
    with pytest.raises(InputError, match="too large to standardise"):
        ResMLPRegressor(max_epochs=2, progress=False).fit(X * 1e300, y, X[:5], y[:5])


def test_random_forest_per_output_is_one_forest_per_target():
    X, y = toy()
    model = TreeRegressor(kind="random_forest", n_estimators=5, per_output=True, n_jobs=-1).fit(X, y)
    assert len(model.estimator_.estimators_) == 2
    assert model.n_nodes_ > 0
    # every fitted forest predicts on one thread (threads would add the trees in finishing order)
    assert [forest.n_jobs for forest in model.estimator_.estimators_] == [1, 1]


def test_unknown_tree_kind_is_a_clear_error():
    with pytest.raises(InputError, match="model.kind must be one of"):
        TreeRegressor(kind="gradient_boosting").fit(*toy())


@pytest.mark.parametrize("kind", ["extra_trees", "random_forest", "decision_tree"])
def test_one_forest_for_several_targets_does_not_depend_on_their_units(kind):
    # One forest adds its targets' squared errors in every split: on raw targets a target in large
    # units (pressure in pascals) would choose every split. Grown on targets divided by their spread,
    # the forest predicts the same x whatever unit the second target is in, and in units.
    X, y = toy(n=300)
    y = np.column_stack([y[:, 0], np.sin(3 * X[:, 3]) + X[:, 4] ** 2])
    params = dict(kind=kind, n_estimators=10, max_features=None, max_depth=None, seed=3)
    in_units = TreeRegressor(**params).fit(X, y).predict(X[:40])
    large = 2.0 ** 17   # a power of two: the standardised targets are then the same to the bit
    scaled = y * np.array([1.0, large])
    in_large_units = TreeRegressor(**params).fit(X, scaled).predict(X[:40])
    np.testing.assert_allclose(in_large_units[:, 0], in_units[:, 0], rtol=1e-9)
    np.testing.assert_allclose(in_large_units[:, 1], large * in_units[:, 1], rtol=1e-9)
    # fully grown trees reproduce their training targets in units
    fitted = TreeRegressor(kind="decision_tree", max_features=None, max_depth=None).fit(X, scaled)
    np.testing.assert_allclose(fitted.predict(X), scaled, rtol=1e-6)
