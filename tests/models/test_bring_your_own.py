"""A model added as docs/add_a_model.md says trains, exports and predicts like the built-in ones:
a scikit-learn regressor and classifier named only by `_target_` in their model config
(configs/model/knn.yaml, configs/model/gradient_boosting.yaml: exported through skl2onnx's own
registry) and a new torch module (models/nets/fcn.py + configs/model/fcn.yaml: trained by the
time-series trainer, exported through torch.onnx). Each goes train -> model.onnx -> predict.py,
whose output must match the eager model on the same inputs."""
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from tests.conftest import tiny
from sklearn.base import BaseEstimator, RegressorMixin

from export.converters.registry import REGISTRY, Piece, convert
from export.graph_builder import GraphBuilder
from models.capabilities import LIBRARY, capabilities
from models.deployable import PIPELINE_FILE, load_pipeline
from runs.run import run

ROOT = Path(__file__).resolve().parents[2]


def predict_py(model: Path, source: Path, output: Path) -> pd.DataFrame:
    done = subprocess.run([sys.executable, str(ROOT / "predict.py"), f"model={model}", f"input={source}",
                           f"output={output}"], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    return pd.read_csv(output)


def pads(path: Path, n: int = 180, seed: int = 0) -> Path:
    """A table of presses on three regions of a pad, its target a class label."""
    rng = np.random.default_rng(seed)
    region = rng.integers(0, 3, n)
    x = np.array([-10.0, 0.0, 10.0])[region] + rng.normal(0, 3, n)
    pd.DataFrame({"r_01_ohm": 1000 + 20 * x + rng.normal(0, 20, n), "r_02_ohm": 1000 - 15 * x + rng.normal(0, 20, n),
                  "region": np.array(["left", "middle", "right"])[region]}).to_csv(path, index=False)
    return path


def test_a_library_regressor_by_its_yaml_alone(compose_config, tmp_path):
    metrics = run(compose_config(tiny("knn") + ["analysis.ablation=false"]), tmp_path)
    assert metrics["model"] == "KNeighborsRegressor" and metrics["test"]["average"]["r2"] > 0.3
    assert (tmp_path / "model.onnx").is_file() and not (tmp_path / PIPELINE_FILE).exists()  # its state: not ours to store
    eager = pd.read_csv(tmp_path / "predictions.csv")       # the run's own predictions, raw readings in front
    onnx = predict_py(tmp_path / "model.onnx", tmp_path / "predictions.csv", tmp_path / "onnx.csv")
    targets = [c for c in onnx.columns if c in eager.columns and not c.startswith("r_")]
    assert targets, onnx.columns
    np.testing.assert_allclose(onnx[targets], eager[targets], rtol=1e-5, atol=1e-6)


def test_a_library_classifier_by_its_yaml_alone(compose_config, tmp_path):
    table = pads(tmp_path / "pads.csv")
    metrics = run(compose_config(["data=table", f"data.path={table}", "data.target_columns=[region]",
                                  "model=gradient_boosting", "model.n_estimators=20"]), tmp_path / "run")
    assert metrics["model"] == "GradientBoostingClassifier" and metrics["calibration"]["method"] is None
    eager = pd.read_csv(tmp_path / "run" / "predictions.csv")
    onnx = predict_py(tmp_path / "run" / "model.onnx", tmp_path / "run" / "predictions.csv", tmp_path / "onnx.csv")
    probabilities = [c for c in onnx.columns if c.startswith("p_")]
    assert probabilities == ["p_left", "p_middle", "p_right"]
    np.testing.assert_allclose(onnx[probabilities], eager[probabilities], atol=1e-6)
    assert (onnx["predicted"] == eager["predicted"]).all()


def test_a_new_torch_module_by_one_file_and_one_yaml(compose_config, tmp_path):
    overrides = ["experiment=materials10", "model=fcn", "model.network.widths=[8,8,8]", "scene.passes_per_level=1",
                 "trainer.max_epochs=1", "trainer.progress=false", "trainer.device=cpu"]
    metrics = run(compose_config(overrides), tmp_path / "run")
    assert metrics["model"] == "FCN" and metrics["n_parameters"] > 0
    pipeline = load_pipeline(tmp_path / "run" / PIPELINE_FILE)   # its state is stored like every net's
    windows = pipeline.examples
    np.savez(tmp_path / "windows.npz", X=windows, channel_names=np.array(pipeline.channel_names))
    onnx = predict_py(tmp_path / "run" / "model.onnx", tmp_path / "windows.npz", tmp_path / "onnx.csv")
    probabilities = [f"p_{c}" for c in pipeline.classes]
    assert len(onnx) == len(windows)   # one window per recording: each example is one model window
    np.testing.assert_allclose(onnx[probabilities].to_numpy(), pipeline.predict_raw(windows), atol=1e-5)


def test_a_class_no_converter_knows_names_itself_and_the_registries():
    class Unknown(RegressorMixin, BaseEstimator):   # an estimator neither registry knows
        pass
    assert capabilities(Unknown()) == LIBRARY
    piece = Piece(GraphBuilder(18), "features", 3, 1, 18, "model")
    with pytest.raises(LookupError, match=rf"test_bring_your_own\..*Unknown in {re.escape(REGISTRY)} nor in skl2onnx's"):
        convert(piece, Unknown())
