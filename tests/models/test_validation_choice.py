"""models/validation_choice.py: candidates fitted cheapest first, scored on validation only, the
best kept (or the validation-weighted mixture when it wins), the budget skipping candidates
before they run, and what was chosen said with its reason."""
import time

import numpy as np
import pytest
from sklearn.base import BaseEstimator, ClassifierMixin, RegressorMixin

from common.errors import InputError
from models.classic_classifiers import TableClassifier
from models.trees import TreeRegressor
from models.validation_choice import ENSEMBLE, ValidationChoice, task_of


class Constant(RegressorMixin, BaseEstimator):
    def __init__(self, value=0.0, sleep_s=0.0):
        self.value = value
        self.sleep_s = sleep_s

    def fit(self, X, y):
        time.sleep(self.sleep_s)
        self.n_outputs_ = np.asarray(y).reshape(len(y), -1).shape[1]
        return self

    def predict(self, X):
        return np.full((len(X), self.n_outputs_), self.value)


class OneFeature(ClassifierMixin, BaseEstimator):
    """Classifies by the sign of one feature, surer the larger it is."""
    def __init__(self, feature=0):
        self.feature = feature

    def fit(self, X, y, X_val=None, y_val=None):
        self.classes_ = np.unique(y)
        self.saw_validation_ = X_val is not None
        return self

    def predict_proba(self, X):
        positive = 1 / (1 + np.exp(-3 * X[:, self.feature]))
        return np.column_stack([1 - positive, positive])


def regression_data(n=300, seed=0):
    rng = np.random.default_rng(seed)
    X = rng.uniform(-2, 2, (n, 3))
    return X, np.column_stack([X[:, 0] + 0.1 * rng.standard_normal(n), X[:, 1] ** 2])


def test_the_best_candidate_on_validation_wins_and_predicts_as_itself():
    X, y = regression_data()
    trees = TreeRegressor(kind="extra_trees", n_estimators=20, max_depth=None, seed=0)
    choice = ValidationChoice({"constant": Constant(), "trees": trees}, ensemble=False)
    choice.fit(X[:200], y[:200], X[200:250], y[200:250])
    assert choice.chosen_ == "trees" and choice.task_ == "regression"
    assert choice.scores_["trees"]["r2"] > 0.5 > choice.scores_["constant"]["r2"]
    np.testing.assert_array_equal(choice.predict(X[250:]), choice.chosen_model_.predict(X[250:]))
    assert "chose trees on validation R^2" in choice.reason_ and choice.report()["chosen"] == "trees"


def test_the_test_rows_never_decide_the_choice():
    """Validation labels that the first candidate predicts and the test rows that only the second does."""
    rng = np.random.default_rng(1)
    X = rng.standard_normal((400, 2))
    y = (X[:, 0] > 0).astype(int)
    X_val = X[300:]
    y_val = (X_val[:, 1] > 0).astype(int)   # feature 1 carries the label on validation only
    choice = ValidationChoice({"first": OneFeature(0), "second": OneFeature(1)}, ensemble=False)
    choice.fit(X[:300], y[:300], X_val, y_val)
    assert choice.chosen_ == "second" and choice.task_ == "classification"
    assert choice.models_["second"].saw_validation_   # passed on to candidates that take it


def test_the_budget_skips_a_candidate_by_its_estimated_cost_before_it_runs():
    X, y = regression_data(60)
    candidates = {"quick": Constant(0.0, sleep_s=0.05), "slow": Constant(1.0, sleep_s=5.0)}
    start = time.perf_counter()
    choice = ValidationChoice(candidates, budget_s=1.0, relative_cost={"quick": 1, "slow": 200}, ensemble=False)
    choice.fit(X[:40], y[:40], X[40:], y[40:])
    assert time.perf_counter() - start < 5.0          # the slow one never ran
    assert set(choice.models_) == {"quick"} and list(choice.skipped_) == ["slow"]
    assert "relative cost 200" in choice.skipped_["slow"] and "budget" in choice.reason_
    # without a budget it runs, cheapest first
    choice = ValidationChoice({"slow": Constant(1.0), "quick": Constant(0.0)}, relative_cost={"slow": 9}).fit(
        X[:40], y[:40], X[40:], y[40:])
    assert list(choice.models_) == ["quick", "slow"] and not choice.skipped_


def test_the_ensemble_is_chosen_only_when_it_wins_on_validation():
    rng = np.random.default_rng(2)
    X = rng.standard_normal((600, 2))
    y = ((X[:, 0] + X[:, 1]) > 0).astype(int)   # each one-feature classifier is right 3/4 of the time
    # the two candidates' mean probability is right more often than either alone
    choice = ValidationChoice({"a": OneFeature(0), "b": OneFeature(1)}).fit(X[:400], y[:400], X[400:], y[400:])
    single = max(choice.scores_["a"]["accuracy"], choice.scores_["b"]["accuracy"])
    assert choice.chosen_ == ENSEMBLE and choice.chosen_model_ is None
    assert choice.scores_[ENSEMBLE]["accuracy"] > single
    np.testing.assert_allclose(sum(choice.ensemble_weights_.values()), 1.0)
    mixed = sum(w * choice.models_[n].predict_proba(X[400:]) for n, w in choice.ensemble_weights_.items())
    np.testing.assert_allclose(choice.predict_proba(X[400:]), mixed)
    # a mixture that does not beat the best candidate is not chosen
    y_easy = (X[:, 0] > 0).astype(int)
    choice = ValidationChoice({"a": OneFeature(0), "b": OneFeature(1)}).fit(X[:400], y_easy[:400], X[400:],
                                                                           y_easy[400:])
    assert choice.chosen_ == "a"


def test_the_candidate_set_follows_the_data_and_a_missing_set_is_one_line():
    assert task_of(np.zeros((4, 2, 10)), np.array([0, 1, 0, 1])) == "recordings"
    assert task_of(np.zeros((4, 2)), np.array([0, 1, 0, 1])) == "classification"
    assert task_of(np.zeros((4, 2)), np.zeros((4, 2))) == "regression"
    X, y = regression_data(80)
    by_task = {"regression": {"constant": Constant()},
               "classification": {"trees": TableClassifier(kind="extra_trees", n_estimators=5)}}
    choice = ValidationChoice(by_task, seed=3).fit(X, y)            # no validation given: carves its own
    assert choice.chosen_ == "constant"
    with pytest.raises(InputError, match="no candidates for recordings data"):
        ValidationChoice(by_task).fit(np.zeros((20, 2, 8)), np.arange(20) % 2)
    with pytest.raises(InputError, match="budget_s must be a positive number"):
        ValidationChoice(by_task, budget_s=-1).fit(X, y)


def test_same_seed_same_choice():
    X, y = regression_data(200)
    make = lambda: ValidationChoice({"a": TreeRegressor(kind="extra_trees", n_estimators=10, seed=0),  # noqa: E731
                                     "b": TreeRegressor(kind="random_forest", n_estimators=10, seed=0)}, seed=4)
    first, second = make().fit(X, y), make().fit(X, y)
    assert first.chosen_ == second.chosen_ and first.scores_ == second.scores_


@pytest.mark.parametrize("n_val, first_wrong, chosen", [(8, 1, "cheap"), (8, 3, "cheap"), (40, 10, "costly")])
def test_a_costlier_classifier_must_be_right_on_significantly_more_validation_rows(n_val, first_wrong, chosen):
    """McNemar on the rows where exactly one is right: one or three recordings of eight are within
    chance (z 1.0, 1.7), ten of forty are not (z 3.2)."""
    rng = np.random.default_rng(0)
    X = rng.standard_normal((100, 2))
    y_val = rng.integers(0, 2, n_val)
    signs = np.where(y_val == 1, 1.0, -1.0)
    X_val = np.column_stack([signs, signs])             # both features carry the label ...
    X_val[:first_wrong, 0] *= -1                        # ... the cheap one's misses a few rows
    choice = ValidationChoice({"cheap": OneFeature(0), "costly": OneFeature(1)}, ensemble=False,
                              relative_cost={"cheap": 1, "costly": 10}, skip_unwinnable=False)
    choice.fit(X, (X[:, 0] > 0).astype(int), X_val, y_val)
    assert choice.scores_["costly"]["accuracy"] == 1.0 > choice.scores_["cheap"]["accuracy"]
    assert choice.chosen_ == chosen
    assert ("not significantly more" in choice.reason_) == (chosen == "cheap")
    with pytest.raises(InputError, match="model.significance_z must be a number >= 0"):
        ValidationChoice({"cheap": OneFeature(0)}, significance_z=-1).fit(X, (X[:, 0] > 0).astype(int), X_val, y_val)


class HeldOut(ClassifierMixin, BaseEstimator):
    """Classifies by the sign of one feature; its held-out predictions of its training rows are
    those of a fit on the other half (two folds), and it counts the rows each fit saw."""
    def __init__(self, feature=0):
        self.feature = feature

    def fit(self, X, y, groups=None):
        self.classes_, self.n_fit_rows_ = np.unique(y), len(X)
        self.out_of_fold_proba_ = self.predict_proba(X)
        self.out_of_fold_method_ = "2 folds"
        return self

    def predict_proba(self, X):
        positive = 1 / (1 + np.exp(-3 * X[:, self.feature]))
        return np.column_stack([1 - positive, positive])


def test_scored_on_training_every_candidate_trains_on_every_row_and_is_scored_on_its_held_out_predictions():
    rng = np.random.default_rng(5)
    X = rng.standard_normal((60, 2))
    y = (X[:, 1] > 0).astype(int)                   # feature 1 carries the label
    choice = ValidationChoice({"first": HeldOut(0), "second": HeldOut(1)}, ensemble=False, score_on="training",
                              relative_cost={"first": 1, "second": 2}).fit(X, y)
    assert {m.n_fit_rows_ for m in choice.models_.values()} == {60}    # no rows carved off for validation
    assert choice.chosen_ == "second" and choice.chosen_model_.n_fit_rows_ == 60
    assert choice.scores_["second"]["accuracy"] == 1.0
    assert choice.scores_["first"]["accuracy"] == float(((X[:, 0] > 0) == y).mean())
    report = choice.report()["scored_on"]
    assert report == {"rows": "training, held out", "n": 60, "by": {"first": "2 folds", "second": "2 folds"}}
    assert "held-out accuracy over all 60 training rows" in choice.reason_ and "second 2 folds" in choice.reason_
    with pytest.raises(InputError, match="validation rows would go unused"):
        ValidationChoice({"a": HeldOut(0)}, score_on="training").fit(X, y, X[:10], y[:10])
    with pytest.raises(InputError, match="candidate plain gives no held-out predictions"):
        ValidationChoice({"plain": OneFeature(0)}, score_on="training").fit(X, y)
    with pytest.raises(InputError, match="regression chooses on validation rows"):
        ValidationChoice({"constant": Constant()}, score_on="training").fit(*regression_data(40))
    with pytest.raises(InputError, match="model.score_on must be one of auto, validation, training"):
        ValidationChoice({"a": HeldOut(0)}, score_on="test").fit(X, y)


def test_the_rocket_familys_held_out_predictions_are_exact_leave_one_out():
    """Each training window's out_of_fold_proba_ is what the head refitted without it (same penalty,
    same features and temperature) predicts; windows sharing a recording are held out by folds."""
    from scipy.special import softmax

    from common.standardise import mean_and_scale
    from models.rocket.classifier import RocketClassifier
    from models.rocket.ridge_loo import class_indicators, ridge_loo
    rng = np.random.default_rng(0)
    y = np.arange(30) % 3
    X = np.sin(2 * np.pi * (1 + y)[:, None, None] * np.linspace(0, 1, 40) + rng.uniform(0, 6, (30, 1, 1)))
    X = X + 0.7 * rng.standard_normal(X.shape)
    model = RocketClassifier(n_features=840).fit(X, y)
    assert model.out_of_fold_method_ == "leave-one-out"
    features = model.transform(X)
    mean, scale = mean_and_scale(features)
    Z, targets = (features - mean) / scale, class_indicators(y, 3)
    for i in (0, 7, 29):
        rest = np.arange(30) != i
        alone = ridge_loo(Z[rest], targets[rest], alphas=[model.alpha_])
        expected = softmax(model.temperature_ * (Z[i] @ alone.coef + alone.intercept))
        np.testing.assert_allclose(model.out_of_fold_proba_[i], expected, rtol=1e-6, atol=1e-9)
    grouped = RocketClassifier(n_features=840).fit(X, y, groups=np.arange(30) // 2)
    assert grouped.out_of_fold_method_ == "3 stratified folds" and grouped.out_of_fold_proba_.shape == (30, 3)


class SlowToPredict(OneFeature):
    """OneFeature that takes `sleep_s` per predict_proba call."""
    def __init__(self, feature=0, sleep_s=0.0):
        super().__init__(feature)
        self.sleep_s = sleep_s

    def predict_proba(self, X):
        time.sleep(self.sleep_s)
        return super().predict_proba(X)


def labelled_by_both(n_val, cheap_wrong, costly_wrong=0):
    """Training rows, and validation rows that feature 0 (the cheap one's) gets wrong on its
    first `cheap_wrong` rows and feature 1 on the `costly_wrong` rows after those."""
    rng = np.random.default_rng(0)
    X = rng.standard_normal((100, 2))
    y_val = rng.integers(0, 2, n_val)
    signs = np.where(y_val == 1, 1.0, -1.0)
    X_val = np.column_stack([signs, signs])
    X_val[:cheap_wrong, 0] *= -1
    X_val[cheap_wrong:cheap_wrong + costly_wrong, 1] *= -1
    return X, (X[:, 0] > 0).astype(int), X_val, y_val


@pytest.mark.parametrize("prefer, chosen", [("cheapest_within_noise", "fast"), ("most_accurate", "slow")])
def test_within_noise_the_cheapest_to_predict_is_kept_and_the_trade_is_said(prefer, chosen):
    """"slow" (costlier to fit and 20 ms per call) is right on 3 more rows of 40 (z 1.7): within noise,
    so cheapest_within_noise keeps "fast" and says what it gave up (3/40, with its paired interval)
    and saved; most_accurate keeps "slow"."""
    X, y, X_val, y_val = labelled_by_both(40, 3)
    choice = ValidationChoice({"fast": SlowToPredict(0), "slow": SlowToPredict(1, sleep_s=0.02)}, ensemble=False,
                              relative_cost={"fast": 1, "slow": 10}, prefer=prefer, skip_unwinnable=False)
    choice.fit(X, y, X_val, y_val)
    assert choice.chosen_ == chosen
    trade = choice.report()["trade"]
    assert trade["kept"] == chosen and trade["most_accurate"] == "slow" and trade["prefer"] == prefer
    assert choice.latency_ms_["slow"] > 15 > choice.latency_ms_["fast"]
    given = trade["accuracy_given_up"]
    if chosen == "fast":
        assert given["difference"] == pytest.approx(3 / 40) and given["gains"] == 3 and given["losses"] == 0
        low, high = given["interval95"]
        assert low < 0 < 3 / 40 < high      # not significant: the interval holds 0
        assert trade["latency_saved_ms"] > 15
        assert "gave up 0.0750 accuracy (95 % interval" in choice.reason_ and "model.prefer=cheapest" in choice.reason_
    else:
        assert given["difference"] == 0 and trade["latency_saved_ms"] == 0


def test_a_costlier_candidate_faster_to_predict_is_kept_within_noise_only_by_a_clear_margin():
    for wrong, slow_s, chosen in ((1, 0.02, "quick_to_predict"), (1, 0.0, "first"), (2, 0.02, "first")):
        X, y, X_val, y_val = labelled_by_both(40, 1, wrong)    # the later one: as accurate, or less (never kept)
        choice = ValidationChoice({"first": SlowToPredict(0, sleep_s=slow_s), "quick_to_predict": SlowToPredict(1)},
                                  ensemble=False, relative_cost={"first": 1, "quick_to_predict": 10},
                                  skip_unwinnable=False)
        choice.fit(X, y, X_val, y_val)
        assert choice.chosen_ == chosen      # equal latencies (both ~0): the first to fit stays


def test_candidates_that_cannot_win_are_not_fitted_and_named_with_the_reason():
    """The cheap one is wrong on 3 of 40: a candidate right on all three reaches z = sqrt(3) = 1.73,
    never significant, so the costly one is skipped; on 10 of 40 it is fitted and wins; with
    most_accurate it is fitted unless the cheap one is never wrong."""
    X, y, X_val, y_val = labelled_by_both(40, 3)
    candidates = {"cheap": OneFeature(0), "costly": OneFeature(1)}
    choice = ValidationChoice(candidates, ensemble=False, relative_cost={"cheap": 1, "costly": 10}).fit(
        X, y, X_val, y_val)
    assert choice.chosen_ == "cheap" and list(choice.models_) == ["cheap"]
    assert "wrong on 3 of 40 scored rows" in choice.skipped_["costly"] and "z = 1.73 <= 1.96" in choice.skipped_["costly"]
    assert "not fitted: costly (cheap is wrong on 3" in choice.reason_
    assert ValidationChoice(candidates, ensemble=False, relative_cost={"cheap": 1, "costly": 10},
                            prefer="most_accurate").fit(X, y, X_val, y_val).chosen_ == "costly"
    X, y, X_val, y_val = labelled_by_both(40, 10)
    assert ValidationChoice(candidates, ensemble=False, relative_cost={"cheap": 1, "costly": 10}).fit(
        X, y, X_val, y_val).chosen_ == "costly"
    X, y, X_val, y_val = labelled_by_both(40, 0)
    most = ValidationChoice(candidates, ensemble=False, relative_cost={"cheap": 1, "costly": 10},
                            prefer="most_accurate").fit(X, y, X_val, y_val)
    assert "right on every held-out row" in most.skipped_["costly"]


def test_a_tie_is_broken_by_cost_and_said():
    X, y, X_val, y_val = labelled_by_both(40, 2, 2)
    for prefer in ("cheapest_within_noise", "most_accurate"):
        choice = ValidationChoice({"a": OneFeature(0), "b": OneFeature(1)}, ensemble=False, prefer=prefer,
                                  relative_cost={"a": 1, "b": 2}, skip_unwinnable=False).fit(X, y, X_val, y_val)
        assert choice.chosen_ == "a" and "a, b tie at held-out accuracy 0.9500; broken by cost" in choice.reason_
        assert choice.report()["ties"].startswith("a, b tie")
    with pytest.raises(InputError, match="model.prefer must be one of cheapest_within_noise, most_accurate"):
        ValidationChoice({"a": OneFeature(0)}, prefer="fastest").fit(X, y, X_val, y_val)


class ShortFitNet(OneFeature):
    """A stand-in net: trained for epochs (max_epochs), each fit noted in `fits`."""
    fits = []

    def __init__(self, feature=0, max_epochs=30):
        super().__init__(feature)
        self.max_epochs = max_epochs

    def __sklearn_tags__(self):
        from models.capabilities import declare
        return declare(super().__sklearn_tags__(), epochs=True)

    def fit(self, X, y, X_val=None, y_val=None):
        ShortFitNet.fits.append((self.feature, self.max_epochs))
        return super().fit(X, y, X_val, y_val)


def test_successive_halving_fits_every_net_short_and_only_the_best_third_in_full():
    rng = np.random.default_rng(0)
    X = rng.standard_normal((100, 4))
    y_val = rng.integers(0, 2, 40)
    X_val = np.repeat(np.where(y_val == 1, 1.0, -1.0)[:, None], 4, axis=1)
    X_val[:10, 0] *= -1                     # the cheap one: 10 of 40 wrong, so the nets could still win
    X_val[10:18, 1] *= -1                   # net a: 8 wrong; net b: none; net c: 12 wrong
    X_val[18:30, 3] *= -1
    ShortFitNet.fits = []
    choice = ValidationChoice({"cheap": OneFeature(0), "a": ShortFitNet(1), "b": ShortFitNet(2), "c": ShortFitNet(3)},
                              ensemble=False, relative_cost={"cheap": 1, "a": 5, "b": 6, "c": 7}, halving=3)
    choice.fit(X, (X[:, 0] > 0).astype(int), X_val, y_val)
    assert ShortFitNet.fits == [(1, 10), (2, 10), (3, 10), (2, 30)]    # three short fits, one full
    assert choice.chosen_ == "b" and set(choice.models_) == {"cheap", "b"}
    assert choice.rungs_["a"] == {"epochs": 10, "accuracy": 0.8, "fit_time_s": pytest.approx(0, abs=1)}
    assert "successive halving: 10 epochs gave held-out accuracy 0.8000 where b gave 1.0000" in choice.skipped_["a"]
    assert list(choice.skipped_) == ["a", "c"] and choice.report()["rungs"]["c"]["accuracy"] == 0.7
    with pytest.raises(InputError, match="model.halving must be a whole number >= 2 or null"):
        ValidationChoice({"cheap": OneFeature(0)}, halving=1).fit(X, (X[:, 0] > 0).astype(int), X_val, y_val)
