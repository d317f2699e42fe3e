"""model=minirocket through train.py's pipeline: a recordings NPZ and the fingertip scene with
virtual force levels, every report file, the exported model.onnx against the eager pipeline, and
predict.py on that export."""
import json

import numpy as np
import onnxruntime as ort
import pandas as pd
import pytest
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

from models.deployable import load_pipeline
from tests.predict_support import predict_main
from runs.run import run
from tests.models.nets.test_nets import assert_predictions_match_metrics, ten_tones_npz

QUICK = ["extras=quick", "trainer.progress=false"]


def test_minirocket_trains_on_a_recordings_file_and_its_export_predicts(compose_config, tmp_path, capsys):
    npz = ten_tones_npz(tmp_path / "tones.npz")
    cfg = compose_config(["data=recordings_npz", f"data.path={npz}", "data.label=y", "model=minirocket", *QUICK])
    metrics = run(cfg, tmp_path / "run")
    run_dir = tmp_path / "run"
    assert metrics["model"] == "MiniRocket" and metrics["n_parameters"] > 84
    assert metrics["val"]["accuracy"] > 0.5 and metrics["test"]["accuracy"] > 0.5      # chance: 0.1
    assert "training" not in metrics                                                    # no epochs to report
    saved = json.loads((run_dir / "metrics.json").read_text())
    assert saved["cost"]["fit_time_s"] > 0 and saved["cost"]["latency_batch1_us"]["onnx_1_thread"]["p50"] > 0
    assert_predictions_match_metrics(run_dir, metrics)
    assert (run_dir / "confusion.png").stat().st_size > 0
    (events,) = (run_dir / "tensorboard").iterdir()
    scalars = EventAccumulator(str(events)).Reload()
    assert scalars.Scalars("final/test_accuracy")[0].value == pytest.approx(metrics["test"]["accuracy"])

    pipeline = load_pipeline(run_dir / "pipeline.npz")
    X = np.load(npz)["X"]
    session = ort.InferenceSession(str(run_dir / "model.onnx"), providers=["CPUExecutionProvider"])
    onnx_proba = session.run(None, {"window": X.astype(np.float32)})[0]
    np.testing.assert_allclose(onnx_proba, pipeline.predict_raw(X), atol=1e-4)

    capsys.readouterr()
    assert predict_main([f"model={run_dir / 'model.onnx'}", f"input={npz}", f"output={tmp_path / 'out.csv'}"]) == 0
    predicted = pd.read_csv(tmp_path / "out.csv")
    expected = np.array(pipeline.classes)[pipeline.predict_raw(X).argmax(1)]
    np.testing.assert_array_equal(predicted["predicted"], expected)
    assert (predicted["predicted"] == np.load(npz)["y"]).mean() > 0.8


def test_minirocket_trains_on_the_fingertip_with_virtual_force_levels(compose_config, tmp_path):
    cfg = compose_config(["experiment=materials10", "augment=virtual_force_levels", "model=minirocket",
                          "scene.passes_per_level=1", *QUICK])
    metrics = run(cfg, tmp_path)
    assert metrics["data"]["n_virtual_windows"] > 0
    assert metrics["val"]["accuracy"] > 0.2 and metrics["test"]["accuracy"] > 0.2      # chance: 0.1
    assert set(metrics["val"]["accuracy_by_force_level_n"]) == {5.0, 20.0}
    assert (tmp_path / "model.onnx").stat().st_size > 0
