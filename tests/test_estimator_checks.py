"""scikit-learn judges the estimator contract: every regressor runs `parametrize_with_checks`.

Each estimator is checked at a tiny size (few epochs, few trees) so the whole set stays fast.
An exception is listed below with its reason; nothing else may fail.
"""
from sklearn.utils.estimator_checks import parametrize_with_checks

from models.kfold_blend import KFoldBlend
from models.resmlp_regressor import ResMLPRegressor
from models.trees import TreeRegressor
from models.weighted_blend import ValidationWeightedBlend


def tiny_net(**kwargs):
    return ResMLPRegressor(widths=(16,), dropouts=(0.0,), noise_std=0.0, max_epochs=40, early_stopping_patience=40,
                           batch_size=16, lr=1e-2, progress=False, **kwargs)


def tiny_forest(kind="extra_trees"):
    return TreeRegressor(kind=kind, n_estimators=10, max_depth=None, max_features=1.0, n_jobs=1)


ESTIMATORS = [
    tiny_net(),
    tiny_forest("random_forest"),
    tiny_forest("extra_trees"),
    TreeRegressor(kind="decision_tree", max_depth=None, max_features=None),
    KFoldBlend(tiny_forest(), n_folds=3, progress=False),
    ValidationWeightedBlend({"et": KFoldBlend(tiny_forest(), n_folds=3, progress=False),
                             "dt": KFoldBlend(TreeRegressor(kind="decision_tree", max_depth=None, max_features=None),
                                              n_folds=3, progress=False)}, weights="stacking"),
    ValidationWeightedBlend({"et": tiny_forest(), "dt": TreeRegressor(kind="decision_tree", max_features=None)},
                            weights="paper"),
]

EXPECTED_FAILURES = {
    "ResMLPRegressor": {
        "check_methods_subset_invariance": "a float32 network: with several BLAS threads a row predicted "
                                           "inside a smaller batch differs from the same row in a full batch by "
                                           "~1e-7 relative (the products are blocked differently), the check's "
                                           "tolerance is 1e-7; with one thread (the tests' default) it passes",
    },
}


def expected_failed_checks(estimator) -> dict:
    return EXPECTED_FAILURES.get(type(estimator).__name__, {})


@parametrize_with_checks(ESTIMATORS, expected_failed_checks=expected_failed_checks)
def test_scikit_learn_estimator_checks(estimator, check):
    check(estimator)
