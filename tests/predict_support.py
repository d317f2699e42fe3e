"""What predict.py's tests share: its main(argv), run in-process, and tiny hand-built ONNX models.

`predict_main(argv)` is predict.py's main loaded from the script (runpy, as `python predict.py`
would run it, minus the exit): the house rule is that nothing imports the entry points, and the
in-process call lets a test run hundreds of cases in a second.

The models carry Touchstone's metadata: built in milliseconds without training, with the same
input and output names, dtypes and metadata keys that export/pipelines.py writes, and any piece
of them can be made wrong on purpose.

- regression: `channels` [batch, 2] float64 -> cast to float32 -> sum per row -> `prediction`
  [batch, 1] float32, so a float64 reading beyond float32's range makes the output inf (as the
  exported graphs' float32 parts would);
- classification of windows: `window` [batch, 2, 4] float32 (raw steps at 100 Hz) -> a weighted
  sum over the window -> softmax -> `probabilities` [batch, 2], so values whose sum overflows
  float32 make them NaN;
- classification of table rows: `channels` [batch, 2] float64 -> cast to float32 -> weighted
  sum -> softmax -> `probabilities` [batch, 2].
"""
import json
import runpy
from pathlib import Path

import numpy as np
import onnx
from onnx import TensorProto, helper

ROOT = Path(__file__).resolve().parents[1]
predict_main = runpy.run_path(str(ROOT / "predict.py"), run_name="predict_script")["main"]

CHANNELS = ["a_ohm", "b_ohm"]
TARGETS = ["x_mm"]
CLASSES = ["soft", "hard"]
WINDOW_STEPS = 4
SAMPLE_RATE_HZ = 100.0


def regression_metadata() -> dict[str, str]:
    return {"kind": "regression", "input": "channels", "channels": json.dumps(CHANNELS),
            "targets": json.dumps(TARGETS), "outputs": json.dumps(["prediction"])}


def classification_metadata() -> dict[str, str]:
    return {"kind": "classification", "input": "window", "channels": json.dumps(CHANNELS),
            "classes": json.dumps(CLASSES), "window_steps": str(WINDOW_STEPS), "sample_rate_hz": str(SAMPLE_RATE_HZ),
            "outputs": json.dumps(["probabilities"])}


def row_classification_metadata() -> dict[str, str]:
    return {"kind": "classification", "input": "channels", "channels": json.dumps(CHANNELS),
            "classes": json.dumps(CLASSES), "outputs": json.dumps(["probabilities"])}


def regression_model(metadata: dict | None = None) -> onnx.ModelProto:
    weights = helper.make_tensor("weights", TensorProto.FLOAT, [len(CHANNELS), len(TARGETS)],
                                 np.ones(len(CHANNELS) * len(TARGETS), dtype=np.float32))
    nodes = [helper.make_node("Cast", ["channels"], ["single"], to=TensorProto.FLOAT),
             helper.make_node("MatMul", ["single", "weights"], ["prediction"])]
    graph = helper.make_graph(nodes, "tiny_regression",
                              [helper.make_tensor_value_info("channels", TensorProto.DOUBLE, ["batch", len(CHANNELS)])],
                              [helper.make_tensor_value_info("prediction", TensorProto.FLOAT, ["batch", len(TARGETS)])],
                              [weights])
    return _model(graph, regression_metadata() if metadata is None else metadata)


def classification_model(metadata: dict | None = None) -> onnx.ModelProto:
    n_in = len(CHANNELS) * WINDOW_STEPS
    weights = helper.make_tensor("weights", TensorProto.FLOAT, [n_in, len(CLASSES)],
                                 np.linspace(-1, 1, n_in * len(CLASSES), dtype=np.float32))
    nodes = [helper.make_node("Flatten", ["window"], ["flat"], axis=1),
             helper.make_node("MatMul", ["flat", "weights"], ["scores"]),
             helper.make_node("Softmax", ["scores"], ["probabilities"], axis=1)]
    graph = helper.make_graph(nodes, "tiny_classification",
                              [helper.make_tensor_value_info("window", TensorProto.FLOAT,
                                                             ["batch", len(CHANNELS), WINDOW_STEPS])],
                              [helper.make_tensor_value_info("probabilities", TensorProto.FLOAT,
                                                             ["batch", len(CLASSES)])],
                              [weights])
    return _model(graph, classification_metadata() if metadata is None else metadata)


def row_classification_model(metadata: dict | None = None) -> onnx.ModelProto:
    weights = helper.make_tensor("weights", TensorProto.FLOAT, [len(CHANNELS), len(CLASSES)],
                                 np.array([1.0, -1.0, -1.0, 1.0], dtype=np.float32))
    nodes = [helper.make_node("Cast", ["channels"], ["single"], to=TensorProto.FLOAT),
             helper.make_node("MatMul", ["single", "weights"], ["scores"]),
             helper.make_node("Softmax", ["scores"], ["probabilities"], axis=1)]
    graph = helper.make_graph(nodes, "tiny_row_classification",
                              [helper.make_tensor_value_info("channels", TensorProto.DOUBLE, ["batch", len(CHANNELS)])],
                              [helper.make_tensor_value_info("probabilities", TensorProto.FLOAT,
                                                             ["batch", len(CLASSES)])],
                              [weights])
    return _model(graph, row_classification_metadata() if metadata is None else metadata)


def _model(graph, metadata: dict) -> onnx.ModelProto:
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 18)], ir_version=10)
    for key, value in metadata.items():
        model.metadata_props.append(onnx.StringStringEntryProto(key=key, value=value))
    return model


def save(model: onnx.ModelProto, path) -> Path:
    path = Path(path)
    path.write_bytes(model.SerializeToString())
    return path


def force_model() -> onnx.ModelProto:
    """The contact tracker's force model as export writes it for experiment=capacitive_force with
    scene.characterisation_channels=window: the 3 x 3 window's loads [batch, 9] float64 ->
    force_n [batch, 1] = 0.01 x their sum."""
    from data.preprocessing.contact_windows import window_channel_names
    channels = window_channel_names()
    weights = helper.make_tensor("weights", TensorProto.FLOAT, [len(channels), 1],
                                 np.full(len(channels), 0.01, dtype=np.float32))
    nodes = [helper.make_node("Cast", ["channels"], ["single"], to=TensorProto.FLOAT),
             helper.make_node("MatMul", ["single", "weights"], ["prediction"])]
    graph = helper.make_graph(nodes, "tiny_force",
                              [helper.make_tensor_value_info("channels", TensorProto.DOUBLE, ["batch", len(channels)])],
                              [helper.make_tensor_value_info("prediction", TensorProto.FLOAT, ["batch", 1])],
                              [weights])
    metadata = {"kind": "regression", "input": "channels", "channels": json.dumps(channels),
                "targets": json.dumps(["force_n"]), "outputs": json.dumps(["prediction"])}
    return _model(graph, metadata)


def contact_frames(n_rest: int = 20, n_press: int = 10, rows: int = 6, cols: int = 6, seed: int = 0) -> np.ndarray:
    """A grid's frames [n, rows * cols]: rest frames (counts near 100), then one press moving
    along the middle row (a bump of 80 counts), as a capacitive skin's firmware streams them."""
    rng = np.random.default_rng(seed)
    frames = 100 + rng.normal(0, 1, (n_rest + n_press, rows * cols))
    y, x = np.mgrid[0:rows, 0:cols]
    for k in range(n_press):
        centre = 1 + (k % (cols - 2))
        frames[n_rest + k] += (80 * np.exp(-((x - centre) ** 2 + (y - rows // 2) ** 2) / 1.0)).ravel()
    return frames
