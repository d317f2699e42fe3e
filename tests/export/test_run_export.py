"""ONNX export of every model family, checked against the eager pipeline with onnxruntime."""
import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import onnx
import pandas as pd
import pytest
from tests.conftest import tiny
from omegaconf import OmegaConf

from common.run_status import config_hash
from data.scenes.fingertip import FingertipScene
from export.onnx_predictor import OnnxPredictor
from export.run_export import export_run
from models.deployable import load_pipeline
from runs.run import run

ROOT = Path(__file__).resolve().parents[2]
REGRESSORS = ["resmlp", "random_forest", "extra_trees", "decision_tree", "blend"]
CLASSIFIERS = ["prcnn", "rescnn", "inceptiontime", "lstm_fcn"]


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """Train and export each family once (tiny settings); reused by the tests below."""
    from hydra import compose, initialize_config_dir
    runs = {}
    for family in REGRESSORS + CLASSIFIERS:
        out = tmp_path_factory.mktemp(family)
        if family in REGRESSORS:
            overrides = tiny(family) + ["analysis.ablation=false"]
        else:
            overrides = ["experiment=materials10", f"model={family}", "scene.passes_per_level=1",
                         "trainer.max_epochs=1", "trainer.progress=false", "trainer.device=cpu"]
        with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
            cfg = compose(config_name="config", overrides=overrides)
        (out / ".hydra").mkdir()
        OmegaConf.save(cfg, out / ".hydra" / "config.yaml")  # as Hydra does: the config hash comes from it
        run(cfg, out)
        runs[family] = (export_run(out), load_pipeline(out / "pipeline.npz"))
    return runs


def hard_readings(n_channels=12):
    rng = np.random.default_rng(0)
    return np.vstack([np.zeros((1, n_channels)), np.full((1, n_channels), 1.7e4), np.full((1, n_channels), 1e-3),
                      np.full((1, n_channels), 1e9), np.r_[np.full(11, 1e9), 0.0][None],
                      10 ** rng.uniform(-3, 9, (2, n_channels)), rng.uniform(1.5e4, 1.8e4, (1017, n_channels))])


@pytest.mark.parametrize("family", REGRESSORS)
def test_regression_graph_matches_the_eager_pipeline(exported, family):
    path, pipeline = exported[family]
    predictor = OnnxPredictor(path)
    readings = hard_readings()
    for batch in (1, 7, 1024):
        out = predictor.predict_array(readings[:batch])
        reference, half = pipeline.predict_raw(readings[:batch])
        assert np.isfinite(out["prediction"]).all()
        scale = np.abs(reference).max(axis=0) + 1e-9
        relative = np.abs(out["prediction"] - reference) / scale
        if family in ("resmlp",):
            # float32 net on readings up to 1e9 ohm: 1e-7 to 1.4e-5 seen, as the trained weights vary
            assert relative.max() < 5e-5, relative.max()
        elif family == "blend":
            assert np.median(relative) < 1e-5 and (relative.max(axis=1) > 1e-3).mean() <= 0.01
        else:
            # float32 trees: a feature exactly on a split threshold may take the other branch
            flipped = (relative.max(axis=1) > 1e-4).mean()
            assert flipped <= 0.01, flipped
        if half is not None:
            assert np.allclose(out["interval_half_width"], half, rtol=1e-3, atol=1e-6 * np.abs(half).max())


@pytest.mark.parametrize("family", CLASSIFIERS)
def test_classification_graph_matches_the_eager_pipeline(exported, family):
    path, pipeline = exported[family]
    predictor = OnnxPredictor(path)
    recordings = FingertipScene(boards=["glass/flat", "resin/circular_5mm"], passes_per_level=1, effects={}).generate()
    windows = recordings.signals[:, :, 40:40 + pipeline.raw_length]
    hard = np.concatenate([windows, np.zeros_like(windows[:1]), np.full_like(windows[:1], 3.3)])
    for batch in (1, 7, len(hard)):
        proba = predictor.predict_windows(hard[:batch])
        np.testing.assert_allclose(proba, pipeline.predict_raw(hard[:batch]), atol=1e-5)
        np.testing.assert_allclose(proba.sum(axis=1), 1.0, atol=1e-5)


def test_exported_file_is_self_contained_and_carries_its_metadata(exported, tmp_path):
    path, pipeline = exported["blend"]
    alone = tmp_path / "robot" / "model.onnx"
    alone.parent.mkdir()
    shutil.copy(path, alone)
    # Self-contained means the export writes model.onnx and nothing else (no external-data
    # sidecar the copy above would have missed): export the same run again, in a copy of its
    # folder without its model.onnx, and compare the folder's listing before and after.
    again = tmp_path / "run"
    shutil.copytree(path.parent, again, ignore=shutil.ignore_patterns(path.name))
    before = sorted(str(p.relative_to(again)) for p in again.rglob("*"))
    assert "pipeline.npz" in before and path.name not in before
    assert export_run(again) == again / path.name
    assert sorted(str(p.relative_to(again)) for p in again.rglob("*")) == sorted(before + [path.name])
    predictor = OnnxPredictor(alone)
    assert predictor.channels == pipeline.channel_names and predictor.targets == pipeline.target_names
    meta = {p.key: p.value for p in onnx.load(alone).metadata_props}
    assert json.loads(meta["features"]) == pipeline.feature_names and len(json.loads(meta["features"])) == 74
    assert json.loads(meta["target_units"])["pressure_pa"] == "pa" and meta["opset"] == "18"
    # the hash of the run's configuration (read back from its .hydra/config.yaml), not of a folder
    # that does not exist yet; another family's configuration has another
    assert meta["config_hash"] == config_hash(OmegaConf.load(path.parent / ".hydra" / "config.yaml"))
    assert meta["config_hash"] != config_hash(OmegaConf.load(exported["resmlp"][0].parent / ".hydra" / "config.yaml"))
    assert meta["touchstone_version"]
    assert predictor.outputs == ["prediction", "interval_half_width"]
    classifier = OnnxPredictor(exported["prcnn"][0])
    assert classifier.classes == exported["prcnn"][1].classes and classifier.window_steps == 1400


def predict(*args, cwd):
    return subprocess.run([sys.executable, str(ROOT / "predict.py"), *args], capture_output=True, text=True, cwd=cwd)


def test_predict_cli_regression_end_to_end_and_bad_input(exported, tmp_path):
    path, pipeline = exported["blend"]
    readings = pd.DataFrame(hard_readings()[:20], columns=pipeline.channel_names)
    readings.to_csv(tmp_path / "rig.csv", index=False)
    result = predict(f"model={path}", f"input={tmp_path / 'rig.csv'}", f"output={tmp_path / 'pred.csv'}", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    pred = pd.read_csv(tmp_path / "pred.csv")
    assert {"x_mm", "depth_mm", "pressure_pa", "x_mm_lower95", "pressure_pa_upper95"} <= set(pred)
    reference, _ = pipeline.predict_raw(readings.to_numpy())
    np.testing.assert_allclose(pred[pipeline.target_names].to_numpy(), reference, rtol=1e-3, atol=1e-3)

    bad = {"missing.csv": readings.drop(columns=["r_05_ohm"]),
           "nan.csv": readings.assign(r_02_ohm=np.nan),
           "text.csv": readings.assign(r_03_ohm="open")}
    messages = {"missing.csv": "missing channel column(s) r_05_ohm", "nan.csv": "'r_02_ohm' has a missing",
                "text.csv": "non-numeric value 'open'"}
    for name, frame in bad.items():
        frame.to_csv(tmp_path / name, index=False)
        out = tmp_path / f"out_{name}"
        result = predict(f"model={path}", f"input={tmp_path / name}", f"output={out}", cwd=tmp_path)
        assert result.returncode == 2 and messages[name] in result.stderr, result.stderr
        assert result.stderr.count("\n") == 1 and not out.exists()
    result = predict(f"model={path}", "input=x.csv", "colour=blue", cwd=tmp_path)
    assert result.returncode == 2 and "unknown argument 'colour=blue'" in result.stderr


def test_predict_cli_classification_and_wrong_window_length(exported, tmp_path):
    path, pipeline = exported["prcnn"]
    recordings = FingertipScene(boards=["resin/circular_5mm"], force_levels_n=[10], passes_per_level=1,
                                effects={}).generate()
    frame = pd.DataFrame(recordings.signals[0].T, columns=recordings.channel_names)
    frame.to_csv(tmp_path / "pass.csv", index=False)
    result = predict(f"model={path}", f"input={tmp_path / 'pass.csv'}", f"output={tmp_path / 'cls.parquet'}", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    classes = pd.read_parquet(tmp_path / "cls.parquet")
    assert len(classes) == recordings.signals.shape[-1] // 1400 and "predicted" in classes
    frame.iloc[:1000].to_csv(tmp_path / "short.csv", index=False)
    result = predict(f"model={path}", f"input={tmp_path / 'short.csv'}", f"output={tmp_path / 'x.csv'}", cwd=tmp_path)
    assert result.returncode == 2 and "shorter than the model's window of 1400 steps" in result.stderr
    assert not (tmp_path / "x.csv").exists()
    with pytest.raises(Exception, match=r"expected windows of shape \(n, 2, 1400\)"):
        OnnxPredictor(path).predict_windows(np.zeros((2, 2, 700)))


def test_export_on_demand_from_a_run_folder(exported, tmp_path):
    path, _ = exported["decision_tree"]
    folder = tmp_path / "copy"
    shutil.copytree(path.parent, folder)
    (folder / "model.onnx").unlink()
    result = subprocess.run([sys.executable, "-m", "export.run_export", str(folder)], capture_output=True, text=True, cwd=ROOT)
    assert result.returncode == 0, result.stderr
    assert (folder / "model.onnx").stat().st_size > 0
    result = subprocess.run([sys.executable, "-m", "export.run_export", str(tmp_path)], capture_output=True, text=True, cwd=ROOT)
    assert result.returncode == 2 and "no pipeline.npz" in result.stderr
