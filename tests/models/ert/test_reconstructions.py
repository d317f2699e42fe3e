"""The ERT reconstructions of models/ert/ (Gauss-Newton with priors, GREIT, the sub-pixel read-out):
the estimator contract, their ONNX graphs in onnxruntime, what each recovers, and that their
hyper-parameters come from validation presses only."""
import numpy as np
import onnxruntime as ort
import pytest

from common.errors import InputError
from data.ert.readings import four_terminal_voltage_v, transfer_basis, unique_transfer_entries
from data.scenes.ert import ERTScene
from export.reconstruction_graphs import linear_image_to_onnx, predict_with_onnx
from models.ert.gauss_newton import GaussNewtonReconstruction
from models.ert.greit import GreitReconstruction
from models.ert.image_readout import thresholded_centroid
from models.ert.pixel_grid import pixel_centres_mm

BOUNDARY = [[15, 120], [50, 120], [85, 120], [120, 85], [120, 50], [120, 15], [85, 0], [50, 0], [15, 0],
            [0, 15], [0, 50], [0, 85]]
SMALL = dict(electrodes_mm=BOUNDARY, side_mm=120.0, grid_nodes=25, patch_mm=20.0,
             force_range_n=(3.0, 12.0), n_force_levels=2, grid_points_per_side=6)
QUIET = {"contact_resistance": {}, "foam_spread": {}}


def scene(**overrides):
    return ERTScene(**{"protocol": "calibration", "effects": QUIET, **SMALL, **overrides})


@pytest.fixture(scope="module")
def calibration():
    s = scene()
    return s, s.generate()


@pytest.fixture(scope="module")
def gauss_newton(calibration):
    s, table = calibration
    return GaussNewtonReconstruction(geometry=s.geometry(), pixels_per_side=12,
                                     lambdas_relative=(1e-3, 1e-2)).fit(table.channels, table.targets)


@pytest.fixture(scope="module")
def greit(calibration):
    s, table = calibration
    training = {**SMALL, "effects": QUIET}
    return GreitReconstruction(geometry=s.geometry(), training_scene=training, pixels_per_side=16, margin_mm=20.0,
                               desired_radius_mm=(10.0,), noise_weights=(1e-3, 1e-2), n_training_sensors=2,
                               presses_per_sensor=150, training_position_range_mm=(0.0, 120.0),
                               training_force_range_n=(3.0, 12.0)).fit(table.channels, table.targets)


def test_channels_are_the_transfer_basis_times_the_unique_transfer_entries():
    s = scene()
    rng = np.random.default_rng(0)
    n = len(BOUNDARY)
    z = np.zeros((n, n))
    a = rng.normal(size=(n - 1, n - 1))
    z[:-1, :-1] = a + a.T                      # symmetric, grounded at the last electrode
    injections, measurements = s.patterns()
    channels = four_terminal_voltage_v(z, injections, measurements, s.current_a).ravel()
    entries = unique_transfer_entries(n)
    assert np.allclose(transfer_basis(s.geometry()) @ z[entries[:, 0], entries[:, 1]], channels)


def test_centroid_read_out_is_sub_pixel_where_the_arg_max_is_not():
    centres = pixel_centres_mm(100.0, 10)                # 10 mm pixels
    truth = np.array([[43.0, 61.5], [12.2, 80.9], [70.7, 30.3]])
    images = np.exp(-((centres[None] - truth[:, None]) ** 2).sum(-1) / (2 * 12.0 ** 2))
    xy, mass = thresholded_centroid(images, centres, 0.5)
    argmax = centres[images.argmax(axis=1)]
    assert np.hypot(*(xy - truth).T).max() < 0.6          # well inside a pixel
    assert np.hypot(*(argmax - truth).T).max() > 2.0
    assert (mass > 0).all()


@pytest.mark.parametrize("name", ["gauss_newton", "greit"])
def test_fit_returns_self_with_learned_state_and_onnx_matches(name, request, calibration):
    model = request.getfixturevalue(name)
    s, table = calibration
    assert model.fit.__self__ is model
    state = [k for k in vars(model) if k.endswith("_")]
    assert {"image_map_", "threshold_", "params_", "force_coefficients_", "n_features_in_"} <= set(state)
    assert not [k for k in vars(model) if k.endswith("_") and k in model.get_params()]
    test = scene(protocol="single_point", grid_points_per_side=5, n_force_levels=1, force_range_n=(8.0, 8.0)).generate()
    eager = model.predict(test.channels)
    assert eager.shape == (len(test.channels), 3) and np.isfinite(eager).all()
    error = np.hypot(*(eager[:, :2] - test.targets[:, :2]).T)
    assert error.mean() < 12.0                                  # 20 mm patches on a 120 mm sheet
    session = ort.InferenceSession(linear_image_to_onnx(model).SerializeToString(), providers=["CPUExecutionProvider"])
    onnx = predict_with_onnx(session, test.channels)
    assert np.allclose(onnx[:, :2], eager[:, :2], atol=0.05)
    assert np.allclose(onnx[:, 2], eager[:, 2], rtol=1e-3, atol=1e-3)


def test_gauss_newton_recovers_a_single_noise_free_perturbation_within_a_few_mm(gauss_newton):
    # presses at patch centres load one patch symmetrically: the image's centroid is the patch centre
    points = np.array([[50.0, 70.0], [30.0, 30.0], [90.0, 50.0], [70.0, 90.0]])
    contacts = np.column_stack([points, np.full(len(points), 8.0)])
    frames = scene(protocol="single_point").simulate(contacts).channels
    xy = gauss_newton.predict(frames)[:, :2]
    assert np.hypot(*(xy - points).T).max() < 3.0


def test_gauss_newton_chooses_among_its_priors_and_rejects_bad_settings(calibration):
    s, table = calibration
    model = GaussNewtonReconstruction(geometry=s.geometry(), pixels_per_side=8, lambdas_relative=(1e-2,))
    model.fit(table.channels, table.targets)
    assert {row["prior"] for row in model.validation_scores_} == {"tikhonov", "laplacian", "noser"}
    assert model.params_["prior"] in ("tikhonov", "laplacian", "noser")
    with pytest.raises(InputError, match="priors"):
        GaussNewtonReconstruction(geometry=s.geometry(), priors=("ridge",)).fit(table.channels, table.targets)
    with pytest.raises(InputError, match="thresholds"):
        GaussNewtonReconstruction(geometry=s.geometry(), thresholds=(1.5,)).fit(table.channels, table.targets)
    with pytest.raises(InputError, match="shape"):
        model.predict(table.channels[:, :5])
    with pytest.raises(InputError, match="NaN"):
        model.predict(np.full_like(table.channels, np.nan))


def test_greit_trains_on_other_sensors_than_the_one_it_reconstructs(greit, calibration):
    assert greit.training_sensor_seeds() == [10_000, 10_001]
    assert calibration[0].seed not in greit.training_sensor_seeds()
    assert greit.image_map_.shape == (16 * 16, len(unique_transfer_entries(len(BOUNDARY))))
    # the image grid reaches past the sheet, so a blob at an edge keeps its centre
    assert greit.pixel_centres_mm_.min() < 0.0 and greit.pixel_centres_mm_.max() > 120.0


TINY = ["scene=ert_boundary", "scene.grid_points_per_side=4", "scene.grid_nodes=21", "scene.injection=adjacent"]


def test_hyper_parameters_are_chosen_on_the_calibration_recording_only(compose_config, tmp_path, monkeypatch):
    from runs.studies.ert_tests import scene_for, single_point_study

    seen = []
    original = GaussNewtonReconstruction.fit

    def spy(self, X, y):
        seen.append(np.asarray(X).copy())
        return original(self, X, y)

    monkeypatch.setattr(GaussNewtonReconstruction, "fit", spy)
    cfg = compose_config(["experiment=ert_localisation", *TINY])
    calibration = {"grid_points_per_side": 4, "n_force_levels": 3, "force_range_n": [2.0, 15.0]}
    frame, extra = single_point_study(cfg, seeds=(0,), calibration=calibration, n_blank=5,
                                  reconstruction={"kind": "gauss_newton", "pixels_per_side": 99,   # Tikhonov's: unused
                                                  "gauss_newton": {"pixels_per_side": 8,
                                                                   "lambdas_relative": [1e-3, 1e-2]}})
    test = scene_for(cfg, seed=0, protocol="single_point", n_force_levels=1, force_range_n=[10.0, 10.0]).generate()
    cal = scene_for(cfg, seed=0, protocol="calibration", **calibration).generate()
    assert len(seen) == 1 and len(frame) == len(test.channels)
    assert extra["loq"][0]["chosen"]["prior"] in ("tikhonov", "laplacian", "noser")
    assert np.array_equal(seen[0], cal.channels)                  # the calibration recording, whole
    # no test frame among the frames the choice saw
    assert not (np.abs(seen[0][:, None, :] - test.channels[None]).max(axis=-1) == 0).any()


def test_learned_inverse_trains_on_other_sensors_and_is_scored_on_the_sensor_under_test(compose_config):
    from models.ert.learned_inverse import GreitLearnedInverse
    from runs.studies.ert_tests import fit_reconstruction, scene_for

    cfg = compose_config(["experiment=ert_localisation", *TINY])
    cal = scene_for(cfg, seed=3, protocol="calibration", grid_points_per_side=4).generate()
    params = {"pixels_per_side": 12, "desired_radius_mm": [15.0], "noise_weights": [1e-2], "n_training_sensors": 2,
              "presses_per_sensor": 120, "n_estimators": 20}
    model = fit_reconstruction("greit_learned", cfg, 3, cal.channels, cal.targets, params)
    assert isinstance(model, GreitLearnedInverse)
    assert 3 not in model.greit_.training_sensor_seeds()
    voltages, _ = model.greit_.training_frames()
    assert len(voltages) == 240 and not np.isin(cal.channels[:5], voltages).all()
    prediction = model.predict(cal.channels)
    assert prediction.shape == (len(cal.channels), 3) and np.isfinite(prediction).all()
    with pytest.raises(InputError, match="among the training sensors"):
        greit = {k: v for k, v in params.items() if k != "n_estimators"}      # the regressor's: not GREIT's
        fit_reconstruction("greit", cfg, 10_001, cal.channels, cal.targets, greit | {"training_seed": 10_000})


def test_learned_study_trains_on_another_sensor_instance(compose_config, tmp_path):
    from runs.studies.ert_learned import run_learned

    cfg = compose_config(["experiment=ert_learned", *TINY])
    with pytest.raises(InputError, match="one of the test sensors"):
        run_learned(cfg, tmp_path, None, seeds=(0, 1), train_sensor_offset=1)
    metrics = run_learned(cfg, tmp_path, None, seeds=(0,), n_train=96, recording_presses=48,
                          models={"extra_trees": {"n_estimators": 5}}, train_sensor_offset=1000,
                          calibration={"grid_points_per_side": 4, "n_force_levels": 3, "force_range_n": [2.0, 15.0]},
                          reconstruction={"pixels_per_side": 8}, features="tikhonov_peak_window", half_width_px=1,
                          train_force_range_n=[4.0, 12.0], conformal_on="held_out")
    assert metrics["train_sensor_seeds"] == [1000] and metrics["seeds"] == [0]
    assert metrics["summary"]["extra_trees"]["localisation_mm"]["mean"] > 0


MLP = {"n_training_sensors": 2, "presses_per_sensor": 150, "noise_weights": [1e-5, 1e-4], "width": 16, "epochs": 3,
       "half_width_patches": 1, "n_members": 2}


@pytest.fixture(scope="module")
def learned_mlp_and_calibration():
    from pathlib import Path

    from hydra import compose, initialize_config_dir

    from runs.studies.ert_tests import fit_reconstruction, scene_for

    with initialize_config_dir(config_dir=str(Path(__file__).resolve().parents[3] / "configs"), version_base="1.3"):
        cfg = compose(config_name="config", overrides=["experiment=ert_localisation", *TINY])
    cal = scene_for(cfg, seed=3, protocol="calibration", grid_points_per_side=4).generate()
    return cfg, cal, fit_reconstruction("learned_mlp", cfg, 3, cal.channels, cal.targets, MLP)


def test_learned_mlp_keeps_the_contract_and_its_onnx_graph_equals_predict(learned_mlp_and_calibration):
    from export.torch_graphs import to_onnx

    _, cal, model = learned_mlp_and_calibration
    assert model.fit.__self__ is model
    assert {"module_", "noise_weight_", "validation_scores_", "n_features_in_"} <= {k for k in vars(model) if k.endswith("_")}
    assert model.noise_weight_ in MLP["noise_weights"] and len(model.validation_scores_) == 2
    eager = model.predict(cal.channels)
    assert eager.shape == (len(cal.channels), 3) and np.isfinite(eager).all()
    example = torch_tensor(cal.channels[:2])
    proto = to_onnx(model.module_, example, "voltages", "prediction", opset=17)
    session = ort.InferenceSession(proto.SerializeToString(), providers=["CPUExecutionProvider"])
    onnx = predict_with_onnx(session, cal.channels)
    assert np.allclose(onnx, eager, atol=1e-3, rtol=1e-4)
    with pytest.raises(InputError, match="shape"):
        model.predict(cal.channels[:, :5])
    with pytest.raises(InputError, match="NaN"):
        model.predict(np.full_like(cal.channels, np.nan))


def torch_tensor(array):
    import torch

    return torch.from_numpy(np.array(array, dtype=np.float32))


def test_learned_mlp_never_trains_on_the_sensor_under_test_and_is_deterministic(learned_mlp_and_calibration):
    from runs.studies.ert_tests import fit_reconstruction

    cfg, cal, model = learned_mlp_and_calibration
    assert model.training_sensor_seeds() == [20_000, 20_001] and 3 not in model.training_sensor_seeds()
    with pytest.raises(InputError, match="among the training sensors"):
        fit_reconstruction("learned_mlp", cfg, 20_001, cal.channels, cal.targets, MLP)
    again = fit_reconstruction("learned_mlp", cfg, 3, cal.channels, cal.targets, MLP)
    assert np.array_equal(again.predict(cal.channels), model.predict(cal.channels))
    other = fit_reconstruction("learned_mlp", cfg, 4, cal.channels, cal.targets, MLP)   # another seed: another net
    assert not np.array_equal(other.predict(cal.channels), model.predict(cal.channels))


def test_learned_mlp_predicts_the_mean_of_its_members(learned_mlp_and_calibration):
    import copy

    import torch

    _, cal, model = learned_mlp_and_calibration
    members = model.module_.mlp.nets
    assert len(members) == MLP["n_members"]
    alone = []
    for net in members:                        # the same module with one member's net as its MLP
        single = copy.deepcopy(model.module_)
        single.mlp = copy.deepcopy(net)
        with torch.no_grad():
            alone.append(single(torch_tensor(cal.channels)).numpy())
    assert not np.allclose(alone[0], alone[1])           # different nets
    assert np.allclose(np.mean(alone, axis=0), model.predict(cal.channels), atol=1e-4)


def test_learned_mlp_trains_on_greits_simulated_presses_reduced_sensor_by_sensor(learned_mlp_and_calibration):
    _, _, model = learned_mlp_and_calibration
    readings, targets = model._training_readings()
    voltages, expected = model._simulator().training_frames()          # all training sensors at once
    assert np.array_equal(targets, expected)
    assert np.allclose(readings, (transfer_basis(model.geometry).T @ voltages.T).T, rtol=1e-12, atol=0)


def test_learned_mlp_members_are_a_prefix_so_validation_can_score_every_ensemble_size(learned_mlp_and_calibration):
    """bench/ert_learned_validation.py scores the mean of the first k nets of one fit as the model
    with n_members = k: member k's net must not depend on how many are trained."""
    from models.ert.learned_readings_inverse import MeanOfNets
    from runs.studies.ert_tests import fit_reconstruction

    cfg, cal, model = learned_mlp_and_calibration
    larger = fit_reconstruction("learned_mlp", cfg, 3, cal.channels, cal.targets, {**MLP, "n_members": 3})
    assert larger.noise_weight_ == model.noise_weight_ and len(larger.module_.mlp.nets) == 3
    three = larger.predict(cal.channels)
    larger.module_.mlp = MeanOfNets(list(larger.module_.mlp.nets)[:MLP["n_members"]])
    assert np.array_equal(larger.predict(cal.channels), model.predict(cal.channels))
    assert not np.array_equal(three, model.predict(cal.channels))
