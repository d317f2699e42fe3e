"""K-fold blending, validation-guided weights, conformal intervals, identifiability map."""
import numpy as np
import pytest
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.metrics import r2_score

from common.errors import InputError
from models.kfold_blend import KFoldBlend
from models.trees import TreeRegressor
from models.uncertainty import conformal_quantile, coverage, normalised_scores
from models.weighted_blend import ValidationWeightedBlend, validation_weights
from runs.report.analysis import identifiability_map


class Constant(BaseEstimator, RegressorMixin):
    """A deliberately useless candidate: predicts a fixed (wrong) value."""
    def __init__(self, value=0.0):
        self.value = value

    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
        self.n_outputs_ = np.asarray(y).reshape(len(y), -1).shape[1]
        return self

    def predict(self, X):
        return np.full((len(X), self.n_outputs_), self.value)


def data(n=600, seed=0, noise=0.1):
    rng = np.random.default_rng(seed)
    X = rng.uniform(-2, 2, size=(n, 3))
    y = np.column_stack([np.sin(X[:, 0]) + X[:, 1], X[:, 2] ** 2])
    return X, y + noise * rng.standard_normal(y.shape)


def trees(seed=0):
    return TreeRegressor(kind="extra_trees", n_estimators=30, max_depth=None, max_features=1.0, seed=seed)


def test_blend_of_identical_models_equals_the_model():
    X, y = data()
    single = trees().fit(X[:400], y[:400])
    blend = ValidationWeightedBlend({"a": trees(), "b": trees()}).fit(X[:400], y[:400], X[400:500], y[400:500])
    np.testing.assert_allclose(blend.predict(X[500:]), single.predict(X[500:]), rtol=1e-12)
    np.testing.assert_allclose(blend.weights_, 0.5)


def test_weights_sum_to_one_and_ignore_negative_r2_candidates():
    X, y = data()
    blend = ValidationWeightedBlend({"trees": trees(), "useless": Constant(value=50.0)})
    blend.fit(X[:400], y[:400], X[400:500], y[400:500])
    assert (blend.val_r2_[1] < 0).all()
    np.testing.assert_allclose(blend.weights_.sum(axis=0), 1.0)
    np.testing.assert_array_equal(blend.weights_[1], 0.0)
    assert blend.selected_() == "trees" and blend.fallback_targets_.size == 0


def test_weights_follow_equation_18_to_20_and_argmax():
    scores = np.array([[0.9, -0.2], [0.6, 0.5], [0.3, 0.5]])
    weights, fallback = validation_weights(scores)
    np.testing.assert_allclose(weights[:, 0], [0.5, 1 / 3, 1 / 6])
    np.testing.assert_allclose(weights[:, 1], [0.0, 0.5, 0.5])
    best, _ = validation_weights(scores, mode="argmax")
    np.testing.assert_allclose(best[:, 0], [1, 0, 0])
    np.testing.assert_allclose(best[:, 1], [0, 0.5, 0.5])  # a tie shares the weight
    assert fallback.size == 0


def test_all_scores_non_positive_fall_back_to_equal_weights_without_dividing_by_zero():
    with np.errstate(all="raise"):
        weights, fallback = validation_weights(np.array([[-1.0, 0.4], [0.0, -3.0], [np.nan, 0.1]]))
    np.testing.assert_allclose(weights[:, 0], 1 / 3)
    np.testing.assert_allclose(weights[:, 1], [0.8, 0.0, 0.2])
    assert fallback.tolist() == [0]
    with pytest.raises(InputError, match="model.mode"):
        validation_weights(np.ones((2, 2)), mode="vote")


def test_kfold_blend_averages_its_fold_models_and_keeps_out_of_fold_residuals():
    X, y = data()
    blend = KFoldBlend(trees(), n_folds=4, seed=1, progress=False).fit(X[:400], y[:400])
    assert len(blend.models_) == 4 and len(blend.fold_fit_time_s_) == 4
    folds = np.stack([m.predict(X[400:]) for m in blend.models_])
    np.testing.assert_allclose(blend.predict(X[400:]), folds.mean(axis=0))
    mean, sigma = blend.predict_std(X[400:])
    np.testing.assert_allclose(sigma ** 2, folds.var(axis=0, ddof=1) + blend.data_variance_)
    np.testing.assert_allclose(blend.data_variance_, ((y[:400] - blend.out_of_fold_) ** 2).mean(axis=0))


class RecordRows(Constant):
    """Remembers which rows it was fitted on (column 0 holds the row number)."""
    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
        self.rows_ = np.asarray(X)[:, 0].astype(int)
        return super().fit(X, y)


def test_grouped_kfold_keeps_groups_together():
    X, y = data(200)
    X[:, 0] = np.arange(len(X))
    groups = np.repeat(np.arange(40), 5)
    blend = KFoldBlend(RecordRows(), n_folds=4, progress=False).fit(X, y, groups=groups)
    assert blend.fold_warning_ is None and len(blend.models_) == 4
    for model in blend.models_:  # each fold model saw whole groups only
        unseen = np.setdiff1d(np.arange(len(X)), model.rows_)
        assert not set(groups[model.rows_]) & set(groups[unseen])


def test_conformal_quantile_matches_the_gaussian_and_refuses_tiny_sets():
    scores = np.abs(np.random.default_rng(0).standard_normal((20000, 1)))
    assert conformal_quantile(scores)[0] == pytest.approx(1.96, abs=0.03)
    with pytest.raises(InputError, match="needs at least 19 calibration rows, got 10"):
        conformal_quantile(scores[:10])


def test_calibrated_intervals_cover_95_percent_on_data_with_known_noise():
    # Heteroscedastic noise the model does not know about: raw intervals miss, conformal ones cover.
    rng = np.random.default_rng(3)
    X = rng.uniform(-2, 2, size=(8000, 2))
    y = (np.sin(2 * X[:, 0]) + 0.3 * (1 + np.abs(X[:, 1])) * rng.standard_normal(8000))[:, None]
    model = KFoldBlend(TreeRegressor(kind="extra_trees", n_estimators=40, min_samples_leaf=20, max_features=1.0),
                       n_folds=3, progress=False).fit(X[:3000], y[:3000])
    model.calibrate(X[3000:4000], y[3000:4000])
    _, lower, upper = model.predict_interval(X[4000:], calibrated=True)
    assert coverage(y[4000:], lower, upper)[0] == pytest.approx(0.95, abs=0.02)


def test_normalised_scores_survive_zero_spread():
    scores = normalised_scores(np.ones((3, 1)), np.ones((3, 1)), np.zeros((3, 1)))
    assert np.isfinite(scores).all()


def test_identifiability_map_has_its_shape_and_is_finite_where_data_are():
    rng = np.random.default_rng(0)
    n = 500
    y = np.column_stack([rng.uniform(0, 50, n), rng.uniform(0, 50, n), rng.uniform(0.3, 3, n), rng.uniform(1e4, 1e5, n)])
    sigma, error = rng.uniform(0.1, 1, (n, 4)), rng.uniform(0, 1, (n, 4))
    targets = ["x_mm", "y_mm", "depth_mm", "pressure_pa"]
    result = identifiability_map(y[:, :2], y[:, 2], sigma, error, targets, bins=4, depth_bins=5)
    grid = np.asarray(result["position_sigma_mm"])
    assert grid.shape == (4, 4) and np.isfinite(grid).all()
    assert len(result["by_depth"]["depth_mm"]["sigma"]) == 5
    assert np.isfinite(result["by_depth"]["pressure_pa"]["abs_error"]).all()


def test_selection_is_deterministic_under_the_seed():
    X, y = data()
    def fit():
        candidates = {"blended": KFoldBlend(trees(seed=2), n_folds=3, seed=2, progress=False), "single": trees(seed=5)}
        return ValidationWeightedBlend(candidates).fit(X[:400], y[:400], X[400:500], y[400:500])
    a, b = fit(), fit()
    np.testing.assert_array_equal(a.weights_, b.weights_)
    # forests sum their trees across threads in arrival order: equal to the last bit or two
    np.testing.assert_allclose(a.predict_std(X[500:])[1], b.predict_std(X[500:])[1], rtol=1e-12)


class FitRecorder(Constant):
    """Remembers whether fit was shown validation rows (column 0 of X holds the row number)."""
    def fit(self, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
        self.rows_ = np.asarray(X)[:, 0].astype(int)
        self.val_rows_ = None if X_val is None else np.asarray(X_val)[:, 0].astype(int)
        return super().fit(X, y)


def test_fold_models_never_see_their_held_out_fold():
    """The out-of-fold predictions (sigma_data, stacking) come from rows the fold model neither
    trained nor early-stopped on."""
    X, y = data(120)
    X[:, 0] = np.arange(len(X))
    blend = KFoldBlend(FitRecorder(), n_folds=4, progress=False).fit(X, y, X[:10], y[:10])
    for model in blend.models_:
        assert model.val_rows_ is None  # no validation rows handed down: a net carves its own
        assert len(model.rows_) == 90


def test_a_net_carves_its_early_stopping_rows_by_group():
    from data.splits.indices import carve_validation
    from models.resmlp_regressor import ResMLPRegressor
    groups = np.repeat(np.arange(30), 4)
    fit_rows, val_rows = carve_validation(len(groups), 0.2, seed=3, groups=groups)
    assert not set(groups[fit_rows]) & set(groups[val_rows]) and len(val_rows) > 0
    X, y = data(120)
    net = ResMLPRegressor(widths=(8,), dropouts=(0.0,), max_epochs=3, progress=False).fit(X, y, groups=groups)
    assert net.n_epochs_ == 3


def hard_candidates(seed=0):
    """Three K-fold candidates of different strength: stacking must beat or equal the best."""
    return {"trees": KFoldBlend(trees(seed), n_folds=3, seed=seed, progress=False),
            "shallow": KFoldBlend(TreeRegressor(kind="decision_tree", max_depth=3, max_features=None, seed=seed),
                                  n_folds=3, seed=seed, progress=False),
            "constant": KFoldBlend(Constant(0.3), n_folds=3, seed=seed, progress=False)}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_stacking_is_never_worse_than_its_best_candidate_on_validation(seed):
    X, y = data(500, seed=seed, noise=0.3)
    blend = ValidationWeightedBlend(hard_candidates(seed), weights="stacking").fit(X[:300], y[:300], X[300:400], y[300:400])
    val_r2 = np.array([r2_score(y[300:400][:, k], blend.predict(X[300:400])[:, k]) for k in range(2)])
    assert (val_r2 >= blend.val_r2_.max(axis=0) - 1e-12).all()
    np.testing.assert_allclose(blend.weights_.sum(axis=0), 1.0)
    assert (blend.weights_ >= 0).all() and blend.weights_[2].max() < 0.05  # the constant is left out
    # the seed's rule gives the useless constant a share whenever its R^2 is positive; stacking
    # is at least as good on validation
    paper = blend.reweighted("paper")
    paper_r2 = np.array([r2_score(y[300:400][:, k], paper.predict(X[300:400])[:, k]) for k in range(2)])
    assert (val_r2 >= paper_r2 - 1e-12).all()


def test_stacking_weights_solve_the_constrained_least_squares():
    from models.weighted_blend import stacking_weights
    rng = np.random.default_rng(0)
    truth = rng.standard_normal(400)
    good, noisy = truth + 0.1 * rng.standard_normal(400), truth + 1.0 * rng.standard_normal(400)
    weights = stacking_weights(np.column_stack([good, noisy, -truth]), truth)
    assert weights.sum() == pytest.approx(1.0) and (weights >= 0).all()
    # inverse-variance weighting of two independent unbiased predictors: 1/0.01 : 1/1
    assert weights[0] == pytest.approx(100 / 101, abs=0.02) and weights[2] < 0.02


def test_stacking_needs_out_of_fold_predictions():
    X, y = data(200)
    with pytest.raises(InputError, match="needs out-of-fold predictions.*single"):
        ValidationWeightedBlend({"single": trees()}, weights="stacking").fit(X, y)


def test_the_blend_carves_its_own_validation_rows():
    X, y = data(200)
    blend = ValidationWeightedBlend({"a": trees(), "b": Constant()}).fit(X, y)
    assert len(blend.y_val_) == 30 and blend.weights_.shape == (2, 2)
