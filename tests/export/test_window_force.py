"""The window force reader: the checked and the live (unchecked) forms give the same forces, and a
model that does not read the 3x3 window to force_n is refused with the caller's name."""
import numpy as np
import pytest
from tests.predict_support import force_model, regression_model, save

from common.errors import InputError
from export.onnx_predictor import OnnxPredictor
from export.window_force import window_force


def test_checked_and_live_readers_agree(tmp_path):
    predictor = OnnxPredictor(save(force_model(), tmp_path / "force.onnx"), threads=1)
    windows = np.random.default_rng(0).uniform(0, 50, (7, 9))
    checked = window_force(predictor, "test")(windows)
    live = window_force(predictor, "test", checked=False)(windows)
    assert checked.shape == (7,)
    np.testing.assert_allclose(live, checked, rtol=0, atol=0)
    np.testing.assert_allclose(checked, windows.sum(axis=1) * 0.01, rtol=1e-5)   # the stand-in's weights


def test_a_model_of_other_channels_is_refused_naming_the_caller(tmp_path):
    predictor = OnnxPredictor(save(regression_model(), tmp_path / "reg.onnx"), threads=1)
    with pytest.raises(InputError, match=r"^my caller: .*does not read the 3x3 window to force_n"):
        window_force(predictor, "my caller")
