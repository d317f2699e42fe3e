"""Calibrated intervals that hold: split-conformal calibration on held-out rows brings a 95 %
interval's test coverage to nominal on heteroscedastic data where the raw Gaussian interval
misses it; too few calibration rows are said, not failed on; bounds stay within a target's
physical range in the report and in predict.py alike."""
import json

import numpy as np
import pandas as pd
import pytest

from data.units import clip_to_range
from export.onnx_predictor import OnnxPredictor
from models.kfold_blend import KFoldBlend
from models.trees import TreeRegressor
from models.uncertainty import coverage
from runs.run import run


def bounded_noise(n, rng):
    """y = a smooth function of x plus uniform noise: 1.96 times its standard deviation reaches
    past its ends, so the raw Gaussian interval covers nearly every row, not 95 % of them."""
    X = rng.uniform(-1, 1, size=(n, 3))
    noise = rng.uniform(-0.8, 0.8, size=n)
    y = np.column_stack([np.sin(3 * X[:, 0]) + X[:, 2] + noise, 2.0 + X[:, 0] + 0.3 * noise])
    return X, y


def test_conformal_calibration_brings_coverage_to_nominal_over_seeds():
    covered_raw, covered = [], []
    for seed in range(3):
        rng = np.random.default_rng(seed)
        X, y = bounded_noise(3000, rng)
        fit, cal, test = np.split(np.arange(3000), [1200, 1800])
        model = KFoldBlend(TreeRegressor(n_estimators=15, max_depth=8, n_jobs=1, seed=seed), n_folds=3, seed=seed,
                           progress=False).fit(X[fit], y[fit])
        model.calibrate(X[cal], y[cal])
        assert model.calibration_note_ is None
        covered_raw.append(coverage(y[test], *model.predict_interval(X[test], calibrated=False)[1:]))
        covered.append(coverage(y[test], *model.predict_interval(X[test], calibrated=True)[1:]))
    covered_raw, covered = np.array(covered_raw), np.array(covered)
    assert covered_raw.mean(axis=0).min() > 0.98                         # the raw interval misses nominal ...
    np.testing.assert_allclose(covered.mean(axis=0), 0.95, atol=0.02)    # ... the calibrated one holds it
    assert covered.min() > 0.92


def test_too_few_calibration_rows_keep_the_raw_interval_and_say_so():
    rng = np.random.default_rng(0)
    X, y = bounded_noise(200, rng)
    model = KFoldBlend(TreeRegressor(n_estimators=5, n_jobs=1), n_folds=2, progress=False).fit(X[:150], y[:150])
    model.calibrate(X[150:160], y[150:160])
    np.testing.assert_allclose(model.conformal_scale_, 1.959964, atol=1e-6)
    assert model.calibration_note_.startswith("too few calibration rows for a conformal 95 % interval (10 < 19)")


def test_bounds_are_clipped_to_the_physical_range_only_where_the_unit_has_one():
    values = np.array([-3.0, 0.5, 7.0])
    np.testing.assert_array_equal(clip_to_range(values, "pressure_pa"), [0.0, 0.5, 7.0])
    np.testing.assert_array_equal(clip_to_range(values, "depth_mm"), [0.0, 0.5, 7.0])
    np.testing.assert_array_equal(clip_to_range(values, "x_mm"), values)          # a coordinate: signed
    np.testing.assert_array_equal(clip_to_range(values, "shear_x_n"), values)     # a force component: signed


def test_a_runs_pressure_bounds_are_non_negative_in_the_report_and_in_predict(compose_config, tmp_path):
    rng = np.random.default_rng(0)
    n = 240
    depth = rng.uniform(0.0, 2.0, n)
    pressure = np.maximum(4000.0 * depth ** 2 + rng.normal(0, 800, n), 0.0)   # many presses near 0 Pa
    frame = pd.DataFrame({"r_1_ohm": 1000 - 100 * depth + rng.normal(0, 30, n), "r_2_ohm": 900 + rng.normal(0, 30, n),
                          "depth_mm": depth, "pressure_pa": pressure})
    path = tmp_path / "rig.csv"
    frame.to_csv(path, index=False)
    cfg = compose_config(["data=table", f"data.path={path}", "data.target_columns=[depth_mm,pressure_pa]",
                          "model=blend", "data.n_folds=2", "extras=quick", "trainer.max_epochs=3", "trainer.progress=false",
                          "model.candidates.random_forest.estimator.n_estimators=10",
                          "model.candidates.extra_trees.estimator.n_estimators=10"])
    metrics = run(cfg, tmp_path / "run")
    data = metrics["data"]
    assert metrics["uncertainty"]["calibration_rows"] == data["n_calibration"] + data["n_val"] >= 19
    predictions = pd.read_csv(tmp_path / "run" / "predictions.csv")
    assert (predictions["pressure_pa_lower95"] == 0.0).any()    # clipped, not merely positive by chance
    assert (predictions[["pressure_pa", "pressure_pa_lower95", "depth_mm", "depth_mm_lower95"]] >= 0.0).all().all()
    predicted = OnnxPredictor(tmp_path / "run" / "model.onnx").predict_table(predictions, "predictions.csv")
    for column in ("pressure_pa", "pressure_pa_lower95", "pressure_pa_upper95", "depth_mm_lower95"):
        np.testing.assert_allclose(predicted[column], predictions[column], rtol=1e-4, atol=1e-3)
    saved = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert saved["uncertainty"]["coverage_calibrated"] == pytest.approx(metrics["uncertainty"]["coverage_calibrated"])
