"""Force from capacitance (seed 001 sec. 3.5): the paper's linear regression, linear-kernel SVR
and Gaussian process (models/classic_regressors.py) obey scikit-learn's contract, learn the
capacitive scene's characterisation through the shared pipeline, and export to ONNX with their
preprocessing, matching the eager pipeline in onnxruntime."""
import numpy as np
import pandas as pd
import pytest
from sklearn.utils.estimator_checks import parametrize_with_checks

from common.errors import InputError
from data.scenes.capacitive6x6 import correlation_factor_rmc_per_n, pressed_cell_rmc
from export.onnx_predictor import OnnxPredictor
from export.run_export import export_run
from models.classic_regressors import ClassicRegressor
from models.deployable import load_pipeline
from runs.run import run

PAPER_MODELS = ["linear_regression", "svr", "gaussian_process"]


@parametrize_with_checks([ClassicRegressor(kind="linear_regression"), ClassicRegressor(kind="svr")])
def test_scikit_learn_estimator_checks(estimator, check):
    check(estimator)


@pytest.mark.slow   # ~15 s: each of ~50 checks optimises a GP's hyper-parameters
@parametrize_with_checks([ClassicRegressor(kind="gaussian_process", max_train_samples=60)])
def test_scikit_learn_estimator_checks_gaussian_process(estimator, check):
    check(estimator)


def test_unknown_kind_and_bad_parameters_are_one_line_errors():
    X, y = np.random.default_rng(0).standard_normal((20, 3)), np.arange(20.0)
    with pytest.raises(InputError, match="model.kind must be one of linear_regression, ridge, svr, gaussian_process"):
        ClassicRegressor(kind="lasso").fit(X, y)
    with pytest.raises(InputError, match="model.svr_c must be > 0"):
        ClassicRegressor(kind="svr", svr_c=0.0).fit(X, y)
    with pytest.raises(InputError, match="max_train_samples must be an integer >= 2"):
        ClassicRegressor(kind="gaussian_process", max_train_samples=1).fit(X, y)


def test_gaussian_process_trains_on_at_most_max_train_samples_rows():
    rng = np.random.default_rng(1)
    X = rng.standard_normal((300, 2))
    model = ClassicRegressor(kind="gaussian_process", max_train_samples=50).fit(X, X[:, 0])
    assert model.n_train_used_ == 50 and model.estimators_[0].X_train_.shape == (50, 2)


def test_linear_models_recover_a_linear_law_in_units():
    rng = np.random.default_rng(2)
    X = rng.standard_normal((200, 4))
    y = np.column_stack([0.02 * X[:, 0] + 1.5, 300.0 * X[:, 1] - 7.0])   # newtons and millimetres
    for kind in ("linear_regression", "svr"):
        pred = ClassicRegressor(kind=kind, svr_epsilon=0.001).fit(X, y).predict(X)
        assert (np.abs(pred - y).max(axis=0) / y.std(axis=0)).max() < 1e-2, kind   # each target in its unit


@pytest.fixture(scope="module")
def force_runs(tmp_path_factory):
    """One tiny characterisation run per paper model through the shared pipeline, exported."""
    from tests.conftest import CONFIG_DIR
    from hydra import compose, initialize_config_dir
    runs = {}
    for model in PAPER_MODELS:
        out = tmp_path_factory.mktemp(model)
        with initialize_config_dir(config_dir=CONFIG_DIR, version_base="1.3"):
            cfg = compose(config_name="config", overrides=[
                "experiment=capacitive_force", f"model={model}", "scene.n_repetitions=12",
                "scene.force_levels_n=[0.1,0.5,1.0,2.0,3.0]", "++model.max_train_samples=200"])
        metrics = run(cfg, out)
        runs[model] = (metrics, export_run(out), load_pipeline(out / "pipeline.npz"), out)
    return runs


@pytest.mark.parametrize("model", PAPER_MODELS)
def test_paper_models_learn_force_from_capacitance(force_runs, model):
    metrics, _, pipeline, _ = force_runs[model]
    assert metrics["test"]["force_n"]["r2"] > 0.98, metrics["test"]["force_n"]
    assert metrics["test"]["force_n"]["rmse"] < 0.2
    assert pipeline.feature_names == [f"raw:{c}" for c in pipeline.channel_names]   # raw RMC only, as the paper


@pytest.mark.parametrize("model", PAPER_MODELS)
def test_exported_graph_matches_the_eager_pipeline(force_runs, model):
    _, path, pipeline, _ = force_runs[model]
    predictor = OnnxPredictor(path)
    examples = pipeline.examples
    n = len(pipeline.channel_names)
    hard = np.vstack([np.zeros((1, n)), np.full((1, n), -30.0), np.full((1, n), 65535.0),
                      np.r_[150.0, np.zeros(n - 1)][None], examples])
    # within 1e-3 of each target's spread over the test presses, plus four float32 steps of the
    # value: the graph's outputs are float32, and the hard rows extrapolate far (a saturated
    # reading to y ~ -46,000 mm, where one float32 step is 0.004 mm, 5e-4 of y's spread)
    spread = pipeline.predict_raw(examples)[0].std(axis=0)
    for batch in (1, 7, len(hard)):
        out = predictor.predict_array(hard[:batch])["prediction"]
        reference, _ = pipeline.predict_raw(hard[:batch])
        assert np.isfinite(out).all()
        tolerance = 1e-3 * spread + 4 * np.finfo(np.float32).eps * np.abs(reference)
        assert (np.abs(out - reference) <= tolerance).all(), model


def test_correlation_factor_is_the_slope_in_counts_per_newton(force_runs):
    """On the run's test presses (the sensor with its effects), a linear model's slope of the
    pressed cell's RMC against its predicted force is the sensor's own slope against the force
    sensor: 1/rho² apart, rho the reading's correlation with force."""
    _, _, _, out = force_runs["linear_regression"]
    predictions = pd.read_csv(out / "predictions.csv")
    presses = predictions.assign(x_mm=predictions["true_x_mm"], y_mm=predictions["true_y_mm"])
    rmc = pressed_cell_rmc(presses, 6, 6, 6.0)
    sensor = correlation_factor_rmc_per_n(rmc, predictions["true_force_n"].to_numpy())
    predicted = predictions["force_n"].to_numpy()
    model = correlation_factor_rmc_per_n(rmc, predicted)
    assert 44 < sensor < 55 and abs(model - sensor) / sensor < 0.05, (sensor, model)
    assert np.isnan(correlation_factor_rmc_per_n(rmc[:1], predicted[:1]))
