"""scikit-learn judges the ERT reconstructions' estimator contract: every class of the registry
(models/ert/registry.py) runs `parametrize_with_checks`, at a tiny size (12 electrodes, adjacent
injections: 144 channels). The checks that cannot apply are listed below with their reason;
nothing else may fail. What those checks would test on their own data (fit returns self, is
idempotent, survives pickling, a clone is unfitted) is tested here on real frames instead."""
import pickle

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.exceptions import NotFittedError
from sklearn.utils.estimator_checks import parametrize_with_checks

from common.errors import InputError
from data.scenes.ert import ERTScene
from models.ert.gauss_newton import GaussNewtonReconstruction
from models.ert.greit import GreitReconstruction
from models.ert.learned_inverse import GreitLearnedInverse
from models.ert.learned_readings_inverse import LearnedReadingsInverse
from models.ert.registry import RECONSTRUCTIONS, reconstruction_class
from models.ert.tikhonov import TikhonovReconstruction

RING = [[15, 120], [50, 120], [85, 120], [120, 85], [120, 50], [120, 15], [85, 0], [50, 0], [15, 0],
        [0, 15], [0, 50], [0, 85]]
SCENE = dict(electrodes_mm=RING, side_mm=120.0, grid_nodes=13, patch_mm=20.0, injection="adjacent",
             effects={"contact_resistance": {}, "foam_spread": {}})
GEOMETRY = ERTScene(**SCENE).geometry()
TINY_GREIT = GreitReconstruction(geometry=GEOMETRY, training_scene=SCENE, pixels_per_side=8, n_training_sensors=1,
                                 presses_per_sensor=20)
ESTIMATORS = [
    TikhonovReconstruction(geometry=GEOMETRY, pixels_per_side=4),
    GaussNewtonReconstruction(geometry=GEOMETRY, pixels_per_side=4),
    TINY_GREIT,
    GreitLearnedInverse(greit=TINY_GREIT, n_estimators=5),
    LearnedReadingsInverse(geometry=GEOMETRY, training_scene=SCENE, n_training_sensors=1, presses_per_sensor=20,
                           epochs=1, n_members=1, width=8),
]

# A frame's width is the geometry's channel count (n_injections x n_measurements: 144 here), and
# the checks below fit on X of their own width (1 to 10 columns): each is refused in one line
# ("voltages must have shape (n_frames, 144)") before anything is learned, so the check cannot
# see what it tests. The same properties are tested on real frames at the end of this file.
FIXED_WIDTH = ("the input width is the geometry's channel count (144); the check fits on X of its own "
               "width, refused in one line before anything is learned")
EXPECTED_FAILURES = {name: FIXED_WIDTH for name in (
    "check_dict_unchanged", "check_dont_overwrite_parameters", "check_dtype_object", "check_estimators_dtypes",
    "check_estimators_fit_returns_self", "check_estimators_overwrite_params", "check_estimators_pickle",
    "check_f_contiguous_array_estimator", "check_fit2d_predict1d", "check_fit_check_is_fitted",
    "check_fit_idempotent", "check_fit_score_takes_y", "check_methods_sample_order_invariance",
    "check_methods_subset_invariance", "check_n_features_in", "check_n_features_in_after_fitting",
    "check_pipeline_consistency", "check_positive_only_tag_during_fit", "check_readonly_memmap_input",
    "check_regressor_data_not_an_array", "check_regressor_multioutput", "check_regressors_int",
    "check_regressors_no_decision_function", "check_regressors_train",
)} | {
    "check_estimators_nan_inf": "NaN and inf are refused ('voltages contain NaN or infinite values'), but only "
                                "after the width, and the check's own X has the wrong width",
    "check_estimators_empty_data_messages": "an empty frame is refused naming the expected channel count, not in "
                                            "scikit-learn's '0 feature(s)' wording",
    "check_fit2d_1sample": "one press is refused for its width first; a reconstruction needs at least 4 presses "
                           "above the quantification limit to choose its settings",
    "check_fit2d_1feature": "a one-column X is refused naming the expected channel count, not in scikit-learn's "
                            "'1 feature(s)' wording",
}


def test_every_registered_reconstruction_is_checked():
    assert {type(estimator) for estimator in ESTIMATORS} == set(RECONSTRUCTIONS.values())


def test_an_unknown_name_is_refused_naming_the_registry():
    assert reconstruction_class("greit") is GreitReconstruction
    with pytest.raises(InputError, match=r"'greitt' is not in the ERT reconstruction registry .*registry\.py"):
        reconstruction_class("greitt")


@parametrize_with_checks(ESTIMATORS, expected_failed_checks=lambda estimator: EXPECTED_FAILURES)
def test_scikit_learn_estimator_checks(estimator, check):
    check(estimator)


@pytest.fixture(scope="module")
def frames():
    scene = ERTScene(protocol="calibration", grid_points_per_side=4, n_force_levels=2, force_range_n=(3.0, 12.0),
                     **SCENE)
    table = scene.generate()
    return table.channels, table.targets


@pytest.mark.parametrize("estimator", ESTIMATORS[:2], ids=lambda e: type(e).__name__)
def test_the_contract_on_real_frames(estimator, frames):
    """What the FIXED_WIDTH checks test, on frames of the geometry's width."""
    X, y = frames
    with pytest.raises(NotFittedError):
        clone(estimator).predict(X)
    fitted = clone(estimator)
    assert fitted.fit(X, y) is fitted and fitted.n_features_in_ == X.shape[1]
    prediction = fitted.predict(X)
    assert prediction.shape == (len(X), 3) and np.isfinite(prediction).all()
    np.testing.assert_array_equal(clone(estimator).fit(X, y).predict(X), prediction)          # idempotent
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(fitted)).predict(X), prediction)
    np.testing.assert_array_equal(fitted.predict(X[::-1])[::-1], prediction)                   # order-free
    assert clone(fitted).get_params().keys() == estimator.get_params().keys()
    with pytest.raises(InputError, match="NaN or infinite"):
        clone(estimator).fit(np.where(np.arange(X.shape[1]) == 3, np.nan, X), y)
