"""model=rocket_mixture (models/rocket/mixture.py): the mixture against its members fitted alone
(model=minirocket and model=hydra_minirocket at the same seed read the same columns of the same
transform), its weights and held-out predictions against their formulas, refusals, and the
default's choice taking it as a candidate. Its ONNX graph: tests/export/converters/test_rocket_mixture.py."""
import numpy as np
import pytest
from sklearn.base import clone

from common.errors import InputError
from models.rocket.classifier import RocketClassifier
from models.rocket.mixture import MixedRocketClassifier
from models.validation_choice import ValidationChoice
from tests.models.rocket.test_hydra import tones

SMALL = {"n_features": 840}


def noisy_tones(n=45, seed=0):
    """Tones under enough noise that the members disagree and err on some recordings."""
    X, y = tones(n=n, length=40, seed=seed)
    return X + 1.5 * np.random.default_rng(seed + 10).standard_normal(X.shape), y


def test_the_mixture_is_its_members_fitted_alone_weighted_by_held_out_accuracy_above_the_majority():
    X, y = noisy_tones()
    X_new, _ = noisy_tones(seed=1)
    members = ("minirocket", "hydra_minirocket")
    mixture = MixedRocketClassifier(seed=2, members=members, **SMALL).fit(X, y)
    alone = {m: RocketClassifier(seed=2, member=m, **SMALL).fit(X, y) for m in members}
    accuracy = {m: float((alone[m].out_of_fold_proba_.argmax(1) == y).mean()) for m in members}
    assert mixture.member_accuracy_ == pytest.approx(accuracy)
    assert 0 < min(accuracy.values()) < 1 and len(set(accuracy.values())) == 2   # members that differ: a real mix
    majority = np.bincount(y).max() / len(y)
    above = {m: accuracy[m] - majority for m in members}
    weights = {m: above[m] / sum(above.values()) for m in members}
    assert mixture.member_weights_ == pytest.approx(weights)
    expected = sum(weights[m] * alone[m].predict_proba(X_new) for m in members)
    np.testing.assert_allclose(mixture.predict_proba(X_new), expected, atol=2e-5)
    np.testing.assert_array_equal(mixture.predict(X_new), mixture.predict_proba(X_new).argmax(1))


def test_held_out_weights_per_window_follow_the_rule_exactly_for_two_members():
    X, y = noisy_tones()
    members = ("minirocket", "hydra_minirocket")
    mixture = MixedRocketClassifier(seed=2, members=members, **SMALL).fit(X, y)
    alone = {m: RocketClassifier(seed=2, member=m, **SMALL).fit(X, y).out_of_fold_proba_ for m in members}
    for i in range(len(y)):
        others = np.arange(len(y)) != i
        floor = np.bincount(y[others], minlength=3).max() / others.sum()
        above = np.array([max((alone[m][others].argmax(1) == y[others]).mean() - floor, 0) for m in members])
        w = above / above.sum() if above.sum() > 0 else np.full(2, 0.5)
        np.testing.assert_allclose(mixture.out_of_fold_proba_[i], w[0] * alone[members[0]][i] + w[1] * alone[members[1]][i],
                                   atol=1e-6)


def test_same_seed_same_mixture_and_clone_refits_it():
    X, y = noisy_tones()
    model = MixedRocketClassifier(seed=5, **SMALL).fit(X, y)
    again = clone(model).fit(X, y)
    np.testing.assert_array_equal(model.predict_proba(X), again.predict_proba(X))
    assert model.member == "hydra_minirocket" and "member" not in model.get_params()
    assert list(model.member_weights_) == ["minirocket", "hydra", "hydra_minirocket"]   # the three by default
    assert sum(model.member_weights_.values()) == pytest.approx(1.0)
    assert model.out_of_fold_method_ == "leave-one-out, weights without the window"


@pytest.mark.parametrize("members", [("minirocket",), ("minirocket", "minirocket"), ("minirocket", "multirocket")])
def test_a_mixture_of_fewer_than_two_known_members_is_refused(members):
    X, y = tones(n=6)
    with pytest.raises(InputError, match="model.members must be two or more of minirocket, hydra, hydra_minirocket") as raised:
        MixedRocketClassifier(members=members, **SMALL).fit(X, y)
    assert "\n" not in str(raised.value)


def test_the_default_choice_scores_the_mixture_on_its_held_out_predictions_like_any_candidate():
    X, y = noisy_tones(n=60)
    choice = ValidationChoice({"minirocket": RocketClassifier(**SMALL), "rocket_mixture": MixedRocketClassifier(**SMALL)},
                              task="recordings", score_on="training", prefer="most_accurate", skip_unwinnable=False, ensemble=False,
                              relative_cost={"minirocket": 0.3, "rocket_mixture": 1.1}).fit(X, y)
    assert set(choice.scores_) == {"minirocket", "rocket_mixture"}
    assert choice.scored_on_["by"]["rocket_mixture"] == "leave-one-out, weights without the window"
    mixture_accuracy = (choice.models_["rocket_mixture"].out_of_fold_proba_.argmax(1) == y).mean()
    assert choice.scores_["rocket_mixture"]["accuracy"] == pytest.approx(mixture_accuracy)
    best = max(choice.scores_, key=lambda n: (choice.scores_[n]["accuracy"], n == "minirocket"))
    assert choice.chosen_ == best and choice.chosen_model_ is choice.models_[best]
