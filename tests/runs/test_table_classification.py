"""A user's table with a class label as its target: the task follows the target's type, every
row classifier trains, its probabilities are calibrated on held-out rows, and the exported ONNX
model gives the in-memory probabilities."""
import json

import numpy as np
import onnxruntime as ort
import pandas as pd
import pytest
from hydra.utils import instantiate
from sklearn.calibration import CalibratedClassifierCV
from sklearn.ensemble import ExtraTreesClassifier
from sklearn.frozen import FrozenEstimator

from common.errors import InputError
from models.classic_classifiers import calibrated, fit_temperature
from models.deployable import load_pipeline
from runs.run import run

REGIONS = ("left", "middle", "right")


def pads(n=240, seed=0, labels=REGIONS) -> pd.DataFrame:
    """Presses on three regions of a pad: two resistances follow the press's x, one is noise."""
    rng = np.random.default_rng(seed)
    region = rng.integers(0, 3, n)
    x = np.array([-10.0, 0.0, 10.0])[region] + rng.normal(0, 3, n)
    return pd.DataFrame({"r_01_ohm": 1000 + 20 * x + rng.normal(0, 20, n), "r_02_ohm": 1000 - 15 * x + rng.normal(0, 20, n),
                         "r_03_ohm": 900 + rng.normal(0, 30, n), "region": np.asarray(labels)[region]})


def table_run(compose_config, tmp_path, frame, *overrides):
    path = tmp_path / "pads.csv"
    frame.to_csv(path, index=False)
    cfg = compose_config(["data=table", f"data.path={path}", "data.target_columns=[region]", "extras=quick",
                          *overrides])
    return run(cfg, tmp_path / "run"), tmp_path / "run"


def test_a_string_target_trains_exports_and_the_onnx_model_gives_the_same_probabilities(compose_config, tmp_path):
    metrics, run_dir = table_run(compose_config, tmp_path, pads(), "model=extra_trees", "model.n_estimators=30")
    assert metrics["data"]["task"] == "classification" and metrics["data"]["classes"] == list(REGIONS)
    assert metrics["data"]["channels"] == ["r_01_ohm", "r_02_ohm", "r_03_ohm"]   # every numeric column but the target
    assert metrics["test"]["accuracy"] > 0.7                                        # chance is 1/3
    assert np.asarray(metrics["test"]["confusion_matrix"]).sum() == metrics["data"]["n_test"]
    assert metrics["calibration"]["method"] == "temperature" and metrics["calibration"]["rows"] >= 20
    assert (run_dir / "confusion.png").stat().st_size > 0 and (run_dir / "confusion_test.png").stat().st_size > 0

    session = ort.InferenceSession(str(run_dir / "model.onnx"), providers=["CPUExecutionProvider"])
    meta = session.get_modelmeta().custom_metadata_map
    assert meta["kind"] == "classification" and meta["input"] == "channels" and meta["label"] == "region"
    assert json.loads(meta["classes"]) == list(REGIONS) and json.loads(meta["outputs"]) == ["probabilities"]
    predictions = pd.read_csv(run_dir / "predictions.csv")
    readings = predictions[json.loads(meta["channels"])].to_numpy()
    (onnx_proba,) = session.run(None, {"channels": readings})
    eager = load_pipeline(run_dir / "pipeline.npz").predict_raw(readings)
    np.testing.assert_allclose(onnx_proba, eager, atol=1e-4)
    np.testing.assert_allclose(eager, predictions[[f"p_{c}" for c in REGIONS]].to_numpy(), atol=1e-12)
    test = predictions[predictions["split"] == "test"]
    assert (test["true"] == test["predicted"]).mean() == pytest.approx(metrics["test"]["accuracy"])


@pytest.mark.parametrize("model", ["random_forest", "decision_tree", "mlp", "logistic_regression"])
def test_every_row_classifier_trains_and_exports(compose_config, tmp_path, model):
    extra = ["model.n_estimators=20"] if model == "random_forest" else []
    metrics, run_dir = table_run(compose_config, tmp_path, pads(), f"model={model}", *extra)
    assert metrics["model"] == f"TableClassifier({model})" and metrics["test"]["accuracy"] > 0.7
    session = ort.InferenceSession(str(run_dir / "model.onnx"), providers=["CPUExecutionProvider"])
    readings = pd.read_csv(run_dir / "predictions.csv")[["r_01_ohm", "r_02_ohm", "r_03_ohm"]].to_numpy()
    (onnx_proba,) = session.run(None, {"channels": readings})
    np.testing.assert_allclose(onnx_proba, load_pipeline(run_dir / "pipeline.npz").predict_raw(readings), atol=1e-4)


def test_model_blend_classifies_with_extra_trees_not_the_regression_blend(compose_config, tmp_path):
    metrics, _ = table_run(compose_config, tmp_path, pads(n=150), "model=blend", "classifier.n_estimators=20")
    assert metrics["model"] == "TableClassifier(extra_trees)"


def test_the_default_model_chooses_among_the_table_classifiers_on_validation(compose_config, tmp_path):
    metrics, run_dir = table_run(compose_config, tmp_path, pads(n=150),
                                 "model.candidates.classification.extra_trees.n_estimators=10",
                                 "model.candidates.classification.random_forest.n_estimators=10")
    choice = metrics["choice"]
    assert choice["task"] == "classification" and set(choice["validation"]) == {
        "logistic_regression", "mlp", "extra_trees", "random_forest"}
    best = max(choice["validation"].values(), key=lambda s: s["accuracy"])["accuracy"]
    if choice["validation"][choice["chosen"]]["accuracy"] < best:   # a cheaper one kept: said, with the test
        assert "not significantly more (McNemar" in choice["reason"]
    assert metrics["model"] == f"TableClassifier({choice['chosen']})"
    assert metrics["val"]["accuracy"] == choice["validation"][choice["chosen"]]["accuracy"]
    assert json.loads((run_dir / "metrics.json").read_text())["choice"]["reason"].startswith(f"chose {choice['chosen']}")


def test_an_integer_coded_target_is_a_class_label_and_the_task_can_be_forced(compose_config, tmp_path):
    frame = pads(labels=(3, 7, 12))
    metrics, _ = table_run(compose_config, tmp_path, frame, "model=decision_tree")
    assert metrics["data"]["task"] == "classification" and metrics["data"]["classes"] == ["3", "7", "12"]
    metrics, _ = table_run(compose_config, tmp_path, frame, "model=decision_tree", "data.task=regression")
    assert metrics["data"]["task"] == "regression" and "r2" in json.dumps(metrics["test"])
    with pytest.raises(InputError, match=r"model.kind=logistic_regression classifies, but .* set data.task=classification"):
        table_run(compose_config, tmp_path, frame, "model=logistic_regression", "data.task=regression")


def test_a_numeric_target_with_a_unit_is_a_quantity_and_a_regressor_is_refused_for_classes(compose_config, tmp_path):
    frame = pads().assign(region=lambda f: np.round(np.abs(f["r_01_ohm"] - 1000) / 100).astype(int)).rename(
        columns={"region": "depth_mm"})
    path = tmp_path / "depth.csv"
    frame.to_csv(path, index=False)
    dm = instantiate(compose_config(["data=table", f"data.path={path}", "data.target_columns=[depth_mm]"]).data).setup()
    assert dm.task == "regression"   # whole millimetres, a unit: a quantity
    with pytest.raises(InputError, match=r"^ClassicRegressor\(kind=svr\) is a regression model; a classification table "
                                         r"trains model=extra_trees"):
        table_run(compose_config, tmp_path, pads(), "model=svr")


def test_a_class_without_training_rows_is_refused_before_fitting(compose_config, tmp_path):
    frame = pads(n=60)
    frame["split"] = "train"
    frame.loc[frame.index[-12:], "split"] = "test"
    frame.loc[frame.index[-1], "region"] = "corner"   # only in test
    with pytest.raises(InputError, match=r"class 'corner' of region has test rows but no training rows"):
        table_run(compose_config, tmp_path, frame, "model=decision_tree")


def test_too_few_calibration_rows_are_said_and_leave_the_probabilities_as_they_are(compose_config, tmp_path):
    metrics, _ = table_run(compose_config, tmp_path, pads(n=60), "model=decision_tree")
    assert metrics["calibration"]["method"] is None and "too few calibration rows" in metrics["calibration"]["note"]


def test_temperature_scaling_matches_scikit_learns():
    rng = np.random.default_rng(1)
    X = rng.normal(size=(600, 4))
    y = np.digitize(X[:, 0] + 0.7 * rng.normal(size=600), [-1.0, 0.0, 1.0])
    clf = ExtraTreesClassifier(40, random_state=0).fit(X[:300], y[:300])
    reference = CalibratedClassifierCV(FrozenEstimator(clf), method="temperature").fit(X[300:450], y[300:450])
    beta = fit_temperature(clf.predict_proba(X[300:450]), y[300:450])
    assert beta != pytest.approx(1.0, abs=0.05)   # the trees are over- or under-confident: a real correction
    np.testing.assert_allclose(calibrated(clf.predict_proba(X[450:]), beta), reference.predict_proba(X[450:]),
                               atol=1e-6)
