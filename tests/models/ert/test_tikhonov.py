"""Tikhonov reconstruction of the ERT skin: the estimator contract, its ONNX graph in
onnxruntime, and its bad inputs."""
import numpy as np
import onnxruntime as ort
import pytest

from common.errors import InputError
from data.scenes.ert import ERTScene
from export.reconstruction_graphs import predict_with_onnx, tikhonov_to_onnx
from models.ert.tikhonov import (
    TikhonovReconstruction,
    bilinear_matrix,
    wiener_kernel,
)

BOUNDARY = [[15, 120], [50, 120], [85, 120], [120, 85], [120, 50], [120, 15], [85, 0], [50, 0], [15, 0],
            [0, 15], [0, 50], [0, 85]]
SMALL = dict(electrodes_mm=BOUNDARY, side_mm=120.0, grid_nodes=25, patch_mm=20.0,
             force_range_n=(3.0, 12.0), n_force_levels=2, grid_points_per_side=6)


@pytest.fixture(scope="module")
def fitted():
    scene = ERTScene(protocol="calibration", effects={"contact_resistance": {}, "foam_spread": {}}, **SMALL)
    table = scene.generate()
    model = TikhonovReconstruction(geometry=scene.geometry(), pixels_per_side=12,
                                   alpha_relative=(1e-3, 1e-2)).fit(table.channels, table.targets)
    return scene, table, model


def test_fit_returns_self_with_learned_state_and_localises_presses(fitted):
    scene, table, model = fitted
    assert model.alpha_relative_ in (1e-3, 1e-2)
    assert model.inverse_.shape == (144, len(scene.channel_names()))
    prediction = model.predict(table.channels)
    error = np.hypot(*(prediction[:, :2] - table.targets[:, :2]).T)
    assert error.mean() < 20.0                        # 20 mm cells on a 120 mm sheet
    assert np.corrcoef(prediction[:, 2], table.targets[:, 2])[0, 1] > 0.8


def test_peak_window_centres_on_the_image_peak_and_keeps_its_pixels(fitted):
    scene, table, model = fitted
    peak_xy_mm, features = model.peak_window(table.channels[:5], half_width_px=1)
    pixels = model.force_pixels(table.channels[:5])
    assert features.shape == (5, 3 + 9)
    assert np.allclose(features[:, :2], peak_xy_mm)
    assert np.allclose(features[:, 2], pixels.sum(axis=1))
    assert np.allclose(features[:, 3 + 4], pixels.max(axis=1))      # the window's centre is the peak
    assert (np.abs(peak_xy_mm - table.targets[:5, :2]) <= 30.0).all()
    # a blank frame peaks at the first pixel, the corner: its window reaches off the sheet (zeros)
    corner_xy_mm, corner = model.peak_window(np.zeros((1, table.channels.shape[1])), half_width_px=1)
    assert np.allclose(corner_xy_mm, 5.0) and np.array_equal(corner[0, 3:], np.zeros(9))   # 10 mm pixels


def test_pressure_field_integrates_to_the_predicted_force(fitted):
    _, table, model = fitted
    field = model.pressure_field_kpa(table.channels[:3])
    assert field.shape == (3, 100, 100)
    pixel_area_mm2 = (120.0 / 12) ** 2
    force = model.force_pixels(table.channels[:3]).sum(axis=1)
    np.testing.assert_allclose(force, model.predict(table.channels[:3])[:, 2])
    # the upsampled field's peak is the predicted position
    peak = np.unravel_index(field.reshape(3, -1).argmax(axis=1), (100, 100))
    np.testing.assert_allclose((peak[1] + 0.5) * 1.2, model.predict(table.channels[:3])[:, 0])
    assert np.isfinite(field).all() and pixel_area_mm2 > 0


def test_onnx_graph_matches_the_estimator_in_onnxruntime(fitted):
    _, table, model = fitted
    proto = tikhonov_to_onnx(model)
    session = ort.InferenceSession(proto.SerializeToString(), providers=["CPUExecutionProvider"])
    expected = model.predict(table.channels)
    got = predict_with_onnx(session, table.channels)
    np.testing.assert_allclose(got[:, 2], expected[:, 2], rtol=1e-3, atol=1e-3 * np.abs(expected[:, 2]).max())
    # float32 may pick another peak where two are tied to float32 precision: the peak it picks
    # must then be as high, in the float64 field, as the estimator's (to 1e-4 of the peak)
    position = np.abs(got[:, :2] - expected[:, :2]).max(axis=1)
    assert (position < 1e-3).mean() > 0.9
    field = model.pressure_field_kpa(table.channels)
    step = model.geometry["side_mm"] / field.shape[-1]
    column, row = (got[:, 0] / step).astype(int), (got[:, 1] / step).astype(int)
    picked = field[np.arange(len(field)), row, column]
    peak = field.reshape(len(field), -1).max(axis=1)
    assert (picked >= peak - 1e-4 * np.abs(peak)).all()


def test_wrong_voltage_length_is_one_line_for_estimator_and_onnx(fitted):
    _, table, model = fitted
    with pytest.raises(InputError, match=r"voltages must have shape \(n_frames, \d+\), got \(2, 5\)"):
        model.predict(np.zeros((2, 5)))
    session = ort.InferenceSession(tikhonov_to_onnx(model).SerializeToString(), providers=["CPUExecutionProvider"])
    with pytest.raises(InputError, match=r"voltages must have shape"):
        predict_with_onnx(session, np.zeros((2, 5)))


@pytest.mark.parametrize("params, message", [
    ({"alpha_relative": (0.0,)}, "alpha_relative must be positive"),
    ({"alpha_relative": (-1e-3, 1e-2)}, "alpha_relative must be positive"),
    ({"regulariser": "tv"}, "regulariser must be identity or laplacian"),
    ({"quantification_limit_n": 50.0}, "no|0 presses at or above the quantification limit"),
])
def test_bad_parameters_are_one_line_input_errors(fitted, params, message):
    scene, table, _ = fitted
    with pytest.raises(InputError, match=message):
        TikhonovReconstruction(geometry=scene.geometry(), pixels_per_side=12, **params).fit(table.channels, table.targets)


def test_deconvolution_kernel_sharpens_a_gaussian_and_keeps_its_sum():
    kernel = wiener_kernel(1.5, 0.01, 4, 16)
    np.testing.assert_allclose(kernel.sum(), 1.0)
    assert kernel[4, 4] > 1.0 and kernel.min() < 0.0          # a sharpening filter


def test_bilinear_upsampling_preserves_constants_and_interpolates():
    matrix = bilinear_matrix(100, 20)
    np.testing.assert_allclose(matrix.sum(axis=1), 1.0)
    ramp = np.arange(20.0)
    up = matrix @ ramp
    assert np.all(np.diff(up) >= 0) and up[0] == 0.0 and up[-1] == 19.0
