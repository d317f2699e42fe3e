"""Findings of the bad-input review: each is a one-line error with exit code 2 (or an InputError
naming the culprit), never a traceback, never a silent acceptance, never a half-written output;
and a model trained on min-max normalised channels deploys on raw ohms."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import onnxruntime as ort
import pandas as pd
import pytest
import torch
from tests.conftest import tiny
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate
from omegaconf import OmegaConf

from common.errors import InputError
from data.preprocessing.features import compute_features
from data.readers.recording_reader import load_npz
from export.onnx_predictor import OnnxPredictor
from export.run_export import export_run
from export.torch_graphs import RegressionFrontEnd, to_onnx
from models.deployable import load_pipeline
from runs.run import run

ROOT = Path(__file__).resolve().parents[2]


def predict(*args, cwd):
    return subprocess.run([sys.executable, str(ROOT / "predict.py"), *args], capture_output=True, text=True, cwd=cwd)


# -- 1. predict.py threads=... --------------------------------------------------------------
@pytest.mark.parametrize("threads", ["abc", "-1", "0.5", ""])
def test_predict_rejects_a_bad_thread_count_in_one_line(tmp_path, threads):
    # parsed before the model is opened, so no model is needed to see the message
    out = tmp_path / "pred.csv"
    result = predict("model=model.onnx", "input=rig.csv", f"output={out}", f"threads={threads}", cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.stderr
    assert "threads must be a non-negative integer" in result.stderr and repr(threads) in result.stderr
    assert not out.exists()


# -- 2. NPZ files are never unpickled --------------------------------------------------------
class Payload:
    """Unpickling this would run code: the file it is saved in must be refused."""

    def __reduce__(self):
        return (Path.touch, (Path("PWNED"),))


def test_npz_with_pickled_objects_is_refused_without_running_them(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    X = np.empty(2, dtype=object)
    X[0], X[1] = Payload(), np.zeros((3, 50))
    np.savez(tmp_path / "evil.npz", X=X, y=np.array(["a", "b"]))
    with pytest.raises(InputError) as error:
        load_npz(tmp_path / "evil.npz")
    message = str(error.value)
    assert not (tmp_path / "PWNED").exists()
    assert "evil.npz" in message and "X" in message and "object" in message and "pickle" in message
    assert "numeric float array X of shape (n, channels, length)" in message and "\n" not in message


def test_npz_of_ragged_recordings_is_refused(tmp_path):
    """The old object-array path (per-recording arrays of different lengths) no longer loads."""
    X = np.empty(2, dtype=object)
    X[0], X[1] = np.zeros((3, 50)), np.zeros((3, 40))
    np.savez(tmp_path / "ragged.npz", X=X, y=np.array(["a", "b"]))
    with pytest.raises(InputError, match=r"ragged.npz: array 'X' is an object \(pickled\) array"):
        load_npz(tmp_path / "ragged.npz")


def test_pickled_npy_given_as_npz_is_refused(tmp_path):
    np.save(tmp_path / "evil.npy", np.array([Payload()], dtype=object))
    with pytest.raises(InputError, match="evil.npy: .*pickled"):
        load_npz(tmp_path / "evil.npy")


# -- 3. labels in an NPZ are present --------------------------------------------------------
def good_X(n=4):
    return np.random.default_rng(0).standard_normal((n, 2, 20))


@pytest.mark.parametrize("arrays, message", [
    ({"y": np.array([0.0, 1.0, 1.0, np.nan])}, r"rig.npz: y\[3\] is missing \(NaN\)"),
    ({"y": np.array([0.0, np.inf, 1.0, 0.0])}, r"rig.npz: y\[1\] is not finite \(inf\)"),
    ({"y": np.array(["glass", "", "resin", "glass"])}, r"rig.npz: y\[1\] is an empty string"),
    ({"y": np.array(["glass", "resin", "  ", "glass"])}, r"rig.npz: y\[2\] is an empty string"),
    ({"y": np.array(list("abab")), "force_level": np.array([1.0, np.nan, 5.0, 5.0])},
     r"rig.npz: force_level\[1\] is missing \(NaN\)"),
    ({"y": np.array(list("abab")), "force_level": np.array([1.0, 5.0, -np.inf, 5.0])},
     r"rig.npz: force_level\[2\] is not finite \(-inf\)"),
    ({"y": np.array(list("abab")), "force_level": np.array([1.0, 5.0, 5.0, -1.0])},
     r"rig.npz: force_level\[3\] is negative \(-1.0 N\)"),
    ({"y": np.array(list("abab")), "force_level": np.array(list("1234"))},
     r"rig.npz: force_level must be numeric \(newtons\)"),
    ({"y": np.array(list("abab")), "force_level": np.array([1.0, 5.0])},
     r"rig.npz: force_level has 2 values for 4 recordings"),
    ({"y": np.array(list("abab")).reshape(2, 2)}, r"rig.npz: y must be one label per recording"),
])
def test_npz_labels_must_be_present_and_force_levels_physical(tmp_path, arrays, message):
    np.savez(tmp_path / "rig.npz", X=good_X(), **arrays)
    with pytest.raises(InputError, match=message) as error:
        load_npz(tmp_path / "rig.npz")
    assert "\n" not in str(error.value)


def test_npz_labels_that_are_present_still_load(tmp_path):
    np.savez(tmp_path / "rig.npz", X=good_X(), y=np.array([0, 1, 0, 1]), force_level=np.array([0.0, 1, 5, 25]))
    recordings = load_npz(tmp_path / "rig.npz", label="surface")
    assert list(recordings.labels["surface"]) == [0, 1, 0, 1]
    assert list(recordings.labels["force_level_n"]) == [0.0, 1.0, 5.0, 25.0]


# -- 5. rubber12_lab: normalised in training, raw ohms in deployment -------------------------
@pytest.fixture(scope="module")
def lab_run(tmp_path_factory):
    """A tiny rubber12_lab run through the real pipeline, exported."""
    out = tmp_path_factory.mktemp("rubber12_lab")
    overrides = tiny("extra_trees") + ["scene=rubber12_lab", "analysis.ablation=false"]
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose(config_name="config", overrides=overrides)
    run(cfg, out)
    return cfg, export_run(out), load_pipeline(out / "pipeline.npz")


def lab_scene(cfg, normalised: bool):
    """The run's own scene, with or without min-max normalisation: every other effect draws from
    its own generator, so the raw ohms are exactly those the normalised channels came from."""
    options = OmegaConf.to_container(cfg.scene, resolve=True)
    if not normalised:
        del options["effects"]["minmax_normalize"]
    return instantiate(options).generate()


def test_lab_pipeline_takes_raw_ohms_and_predicts_what_the_model_learnt(lab_run):
    cfg, _, pipeline = lab_run
    raw, normalised = lab_scene(cfg, normalised=False), lab_scene(cfg, normalised=True)
    assert pipeline.channel_names == raw.channel_columns == [f"r_{k:02d}_ohm" for k in range(1, 13)]
    assert normalised.channel_columns[0] == "r_01_norm" and pipeline.feature_names[0] == "raw:r_01_norm"
    # the constants kept with the data reproduce the lab's normalisation from the raw readings
    scaling = normalised.normalisation
    assert scaling.raw_channels == raw.channel_columns
    np.testing.assert_array_equal(scaling.minimum, raw.channels.min(axis=0))
    np.testing.assert_allclose(scaling.normalise(raw.channels), normalised.channels, rtol=0, atol=1e-15)
    # latency examples are raw readings of the data set (to the rounding of the inverse map)
    nearest = np.abs(pipeline.examples[:, None] - raw.channels[None]).max(axis=2).min(axis=1)
    assert nearest.max() <= 1e-9 * raw.channels.max()

    eager, _ = pipeline.predict_raw(raw.channels)
    features = (compute_features(normalised.channels, pipeline.feature_groups) - pipeline.scaler_mean) / pipeline.scaler_scale
    learnt = np.asarray(pipeline.model.predict(features)).reshape(len(features), -1)
    np.testing.assert_allclose(eager, learnt, rtol=1e-12)  # the forest sums its trees in any order


def test_lab_graph_takes_raw_ohms_and_matches_the_eager_pipeline(lab_run):
    cfg, path, pipeline = lab_run
    raw = lab_scene(cfg, normalised=False).channels
    # the graph's front end (normalisation, features, scaler) is the eager one, to its float32 output
    front = RegressionFrontEnd(pipeline.feature_groups, pipeline.scaler_mean, pipeline.scaler_scale,
                               pipeline.normalisation)
    proto = to_onnx(front, torch.ones(2, 12, dtype=torch.float64), "channels", "features", 18)
    features = ort.InferenceSession(proto.SerializeToString()).run(None, {"channels": raw})[0]
    np.testing.assert_allclose(features, pipeline.features(raw), rtol=1e-6, atol=1e-6)
    # the whole model; float32 trees: a feature exactly on a split threshold may take the other branch
    onnx = OnnxPredictor(path).predict_array(raw)["prediction"]
    eager, _ = pipeline.predict_raw(raw)
    relative = np.abs(onnx - eager).max(axis=1) / np.abs(eager).max()
    assert (relative > 1e-4).mean() <= 0.01, relative.max()


def test_predict_cli_takes_raw_ohm_columns_for_a_lab_model(lab_run, tmp_path):
    cfg, path, pipeline = lab_run
    raw = lab_scene(cfg, normalised=False)
    raw.frame[raw.channel_columns].iloc[:20].to_csv(tmp_path / "robot.csv", index=False)
    result = predict(f"model={path}", f"input={tmp_path / 'robot.csv'}", f"output={tmp_path / 'pred.csv'}", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    predicted = pd.read_csv(tmp_path / "pred.csv")[pipeline.target_names].to_numpy()
    np.testing.assert_allclose(predicted, pipeline.predict_raw(raw.channels[:20])[0], rtol=1e-3, atol=1e-3)
    # the normalised columns the model was trained on are not what it takes
    normalised = lab_scene(cfg, normalised=True)
    normalised.frame[normalised.channel_columns].iloc[:5].to_csv(tmp_path / "norm.csv", index=False)
    result = predict(f"model={path}", f"input={tmp_path / 'norm.csv'}", f"output={tmp_path / 'x.csv'}", cwd=tmp_path)
    assert result.returncode == 2 and "missing channel column(s) r_01_ohm" in result.stderr
    assert result.stderr.count("\n") == 1 and not (tmp_path / "x.csv").exists()  # the model loads quietly
