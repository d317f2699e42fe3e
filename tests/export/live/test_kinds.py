"""The stream kinds: a recordings model's ring holds exactly the newest window at every hop, and
a model that is not the tracker's force model is refused for rows= and cols=."""
import numpy as np
import pytest
from tests.predict_support import WINDOW_STEPS, classification_model, regression_model, save

from common.errors import InputError
from export.live.kinds import TrackerStream, WindowStream
from export.live.summary import ModelTime
from export.onnx_predictor import OnnxPredictor


@pytest.mark.parametrize("hop", [1, 3, WINDOW_STEPS])
def test_the_ring_gives_the_sliding_windows_and_their_predictions(tmp_path, hop):
    predictor = OnnxPredictor(save(classification_model(), tmp_path / "cls.onnx"), threads=1)
    stream = WindowStream(predictor, hop)
    values = np.arange(2 * 23, dtype=float).reshape(23, 2)
    rows = stream.predict([(k + 1, None, v) for k, v in enumerate(values)], ModelTime())
    starts = list(range(0, len(values) - WINDOW_STEPS + 1, hop))
    assert [row[2][0] for row in rows] == [s + 1 for s in starts]            # start_line
    windows = np.stack([values[s:s + WINDOW_STEPS].T for s in starts])
    expected = predictor.predict_windows(windows)
    got = np.array([row[2][2:] for row in rows])
    np.testing.assert_array_equal(got, expected.astype(np.float64))


def test_a_gap_starts_the_window_again(tmp_path):
    predictor = OnnxPredictor(save(classification_model(), tmp_path / "cls.onnx"), threads=1)
    stream = WindowStream(predictor)
    lines = [(k + 1, None, np.array([k, k], dtype=float)) for k in range(WINDOW_STEPS - 1)]
    assert stream.predict(lines, ModelTime()) == []
    stream.gap()
    assert stream.predict(lines, ModelTime()) == []


def test_rows_and_cols_need_the_force_model(tmp_path):
    predictor = OnnxPredictor(save(regression_model(), tmp_path / "reg.onnx"), threads=1)
    with pytest.raises(InputError, match="3x3 window to force_n"):
        TrackerStream(predictor, 6, 6, 10.0, 60)
