"""A user's recordings are taken as they are: no FSR calibration, decimation, trimming or
fingertip-sized windows unless asked for (configs/data/base/timeseries.yaml), while the
fingertip experiments keep the seed paper's preprocessing (configs/data/fingertip.yaml)."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import onnx
import pandas as pd
import pytest
from hydra.utils import instantiate

from common.errors import InputError
from data.readers.recording_reader import load_long_table, load_npz
from export.pipelines import metadata_for
from models.deployable import TimeSeriesPipeline

ROOT = Path(__file__).resolve().parents[2]
NEUTRAL = {"force_calibration": None, "decimate": 1, "window_length": None, "window_step": None, "trim_start": 0,
           "trim_end": 0, "modalities": None, "split": "auto", "declared_split": "use"}
# The seed paper's preprocessing as the fingertip experiments used it before the data options
# became neutral: these must not move (configs/data/fingertip.yaml).
FINGERTIP = {"decimate": 10, "window_length": 140, "window_step": 20, "trim_start": 3, "trim_end": 3,
             "split": "force_level", "train_levels": [1, 10, 15, 25], "val_levels": [5, 20], "test_fraction": 0.5,
             "val_fraction": 0.2, "min_variance": 0.0, "variance_channel": 0,
             "modalities": {"triboelectric": ["triboelectric_na"], "piezoresistive": ["piezoresistive_n"]},
             "force_calibration": {"channel": "piezoresistive_v", "supply_v": 3.3, "reference_v": 0.25,
                                   "feedback_resistor_ohm": 1.8e4, "series_resistor_ohm": 1.0e3,
                                   "fsr_resistance_1n_ohm": 1.0e4, "fsr_exponent": 0.9, "fsr_saturation_n": 22.0}}


@pytest.mark.parametrize("data", ["recordings_npz", "recordings_table", "timeseries"])
def test_users_data_configs_are_neutral_and_take_modalities_plainly(compose_config, data):
    cfg = compose_config([f"data={data}"])
    assert {key: cfg.data[key] for key in NEUTRAL} == NEUTRAL
    cfg = compose_config([f"data={data}", "data.modalities={accel: [0,1,2], gyro: [3,4,5]}"])
    assert cfg.data.modalities == {"accel": [0, 1, 2], "gyro": [3, 4, 5]}


@pytest.mark.parametrize("experiment", ["materials10", "textures13", "combined18", "tsc_accuracy_vs_time"])
def test_fingertip_experiments_keep_the_papers_preprocessing(compose_config, experiment):
    data = compose_config([f"experiment={experiment}"]).data
    assert {key: data[key] for key in FINGERTIP} == FINGERTIP
    assert data.label in ("material", "texture", "board")


def tones_npz(path, steps=100, n=40, split=True, **extra):
    """3-channel series of `steps` steps, two string classes told apart by frequency."""
    rng = np.random.default_rng(0)
    t = np.arange(steps) / 50.0
    y = np.tile(["smooth", "ridged"], n // 2)
    X = np.stack([np.stack([np.sin(2 * np.pi * (2.0 if c == "smooth" else 7.0) * t + rng.uniform(0, 6))
                            + 0.2 * rng.standard_normal(steps) for _ in range(3)]) for c in y])
    arrays = {"X": X.astype(np.float32), "y": y, **extra}
    if split:
        arrays["split"] = np.where(np.arange(n) % 4 == 0, "test", "train")
    np.savez(path, **arrays)
    return path


def test_whole_recordings_are_the_windows_and_labels_stay_names(compose_config, tmp_path):
    path = tones_npz(tmp_path / "rig.npz", sample_rate_hz=np.array(50.0))
    cfg = compose_config(["data=recordings_npz", f"data.path={path}", "data.split=predefined"])
    dm = instantiate(cfg.data).setup()
    assert dm.X_train.shape[1:] == (3, 100)  # 100 steps untouched: no decimation, trimming or cropping
    assert len(dm.X_test) == 10 and dm.classes == ["ridged", "smooth"]
    assert dm.recording_rate_hz == 50.0 and dm.summary()["window_length"] is None
    cfg = compose_config(["data=recordings_npz", f"data.path={path}", "data.window_length=140"])
    with pytest.raises(InputError, match="recordings of 100 steps after trimming are shorter than the window length 140"):
        instantiate(cfg.data).setup()
    cfg = compose_config(["data=recordings_npz", f"data.path={path}", "data.window_length=50"])
    assert instantiate(cfg.data).setup().X_train.shape[1:] == (3, 50)  # window_step null: back to back


def test_sample_rate_is_the_datas_own(tmp_path):
    assert load_npz(tones_npz(tmp_path / "plain.npz")).sample_rate_hz is None  # the NPZ does not say
    assert load_npz(tones_npz(tmp_path / "rated.npz", sample_rate_hz=np.array(1000.0))).sample_rate_hz == 1000.0
    with pytest.raises(InputError, match="data.source.sample_rate_hz=250.0 but the data say 1000 Hz"):
        load_npz(tmp_path / "rated.npz", sample_rate_hz=250.0)
    pipeline = TimeSeriesPipeline(["a"], ["x", "y"], None, 1, 10, np.zeros((1, 1, 1)), np.ones((1, 1, 1)), object(),
                                  {"sample_rate_hz": None})
    assert metadata_for(pipeline, "hash", 18)["sample_rate_hz"] == "unknown"  # never a made-up 250


def unequal_long_table(path):
    rows = [{"recording": r, "time_s": t / 100.0, "ax": float(t), "label": "ab"[r % 2]}
            for r, steps in enumerate([30, 30, 25, 30]) for t in range(steps)]
    pd.DataFrame(rows).to_csv(path, index=False)
    return path


def test_recordings_of_different_lengths_need_a_stated_rule(tmp_path):
    path = unequal_long_table(tmp_path / "rig.csv")
    with pytest.raises(InputError, match=r"different lengths \(25 to 30 steps\); set data.source.lengths=crop"):
        load_long_table(path, "recording", "time_s", ["ax"], ["label"])
    cropped = load_long_table(path, "recording", "time_s", ["ax"], ["label"], lengths="crop")
    padded = load_long_table(path, "recording", "time_s", ["ax"], ["label"], lengths="pad")
    assert cropped.signals.shape == (4, 1, 25) and padded.signals.shape == (4, 1, 30)
    np.testing.assert_array_equal(padded.signals[2, 0, 25:], 0.0)
    np.testing.assert_array_equal(padded.signals[2, 0, :25], np.arange(25.0))
    assert cropped.sample_rate_hz == pytest.approx(100.0)  # one over the median time step


def test_readmes_npz_command_runs_on_100_step_series(tmp_path):
    """The documented "your NPZ" command, end to end through train.py, on 100-step series with a
    declared split and string labels (tiny network, two epochs)."""
    path = tones_npz(tmp_path / "rig.npz", sample_rate_hz=np.array(50.0))
    run_dir = tmp_path / "run"
    command = [sys.executable, str(ROOT / "train.py"), "experiment=materials10", "data=recordings_npz",
               f"data.path={path}", "data.label=y", "data.split=predefined",
               "model.network.branch_width=8", "model.network.fusion_width=8", "trainer.max_epochs=2",
               "trainer.lr_milestones=[1]", "trainer.progress=false", "trainer.device=cpu",
               "cost.measure_latency=false", f"hydra.run.dir={run_dir}"]
    result = subprocess.run(command, capture_output=True, text=True, cwd=tmp_path, timeout=300,
                            env={**os.environ, "CI": "true"})
    assert result.returncode == 0, result.stderr[-2000:]
    metrics = json.loads((run_dir / "metrics.json").read_text())
    assert metrics["data"]["window"] == [3, 100] and metrics["data"]["split"] == "predefined"
    assert metrics["data"]["n_test_recordings"] == 10 and set(metrics["test"]["per_class_accuracy"]) == {"ridged", "smooth"}
    predictions = pd.read_csv(run_dir / "predictions.csv")
    probabilities = predictions[["p_ridged", "p_smooth"]].to_numpy()
    np.testing.assert_allclose(probabilities.sum(axis=1), 1.0, atol=1e-5)
    names = np.array(["ridged", "smooth"])
    assert (predictions["predicted"].to_numpy() == names[probabilities.argmax(axis=1)]).all()
    assert set(predictions["true"]) == {"ridged", "smooth"}
    metadata = {p.key: p.value for p in onnx.load(run_dir / "model.onnx").metadata_props}
    assert metadata["sample_rate_hz"] == "50.0" and json.loads(metadata["classes"]) == ["ridged", "smooth"]
    assert metadata["window_steps"] == "100"


@pytest.mark.slow  # ~10-15 s: a train.py start-up (torch) to see the exit code of an error in the data
def test_a_split_value_typo_is_one_line_and_exit_2(tmp_path):
    path = tones_npz(tmp_path / "rig.npz", split=False)
    with np.load(path) as archive:
        arrays = dict(archive)
    arrays["split"] = np.array(["train"] * 39 + ["tets"])
    np.savez(path, **arrays)
    result = subprocess.run([sys.executable, str(ROOT / "train.py"), "experiment=materials10", "data=recordings_npz",
                             f"data.path={path}", "data.split=predefined", f"hydra.run.dir={tmp_path / 'run'}"],
                            capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert result.returncode == 2, result.stderr[-2000:]
    assert result.stderr.strip() == (f"error: {path}: array 'split': split value 'tets' in split[39] is not one of "
                                     "train, val, test")
    assert not (tmp_path / "run" / "metrics.json").exists()
