"""Run an exported Touchstone model with onnxruntime, checking inputs against its metadata.

    predictor = OnnxPredictor("run/model.onnx")
    predictor.predict_table(frame)      # regression: a frame with the model's channel columns
    predictor.predict_windows(windows)  # classification: (n, channels, steps) raw windows
Every problem with the model file, its metadata or the input is a one-line InputError naming the
file and the key, column or row; a value that is not finite in the graph's input dtype (1e308 in
a float32 graph) is refused before the model runs, and an output that is not finite (an input
outside what the model can compute) is refused before anything is returned.
"""
import json
from pathlib import Path

import numpy as np
import onnxruntime as ort
import pandas as pd

from common.errors import InputError
from common.threads import configured_threads
from data.readers.table_reader import check_numeric_columns, where

KINDS = ("regression", "classification")
# The graph's one input and its first output per kind (export/pipelines.py writes them).
INPUT_NAME = {"regression": "channels", "classification": "window"}
MAIN_OUTPUT = {"regression": "prediction", "classification": "probabilities"}
INPUT_DTYPES = {"tensor(double)": np.float64, "tensor(float)": np.float32}


class OnnxPredictor:
    def __init__(self, path, threads: int | None = None):
        """threads: intra-op threads; None = the Touchstone setting in force (common/threads.py),
        0 = onnxruntime's own default (one per core)."""
        self.path = str(path)
        if not Path(path).is_file():
            raise InputError(f"{path}: no such model file")
        if Path(path).stat().st_size == 0:
            raise InputError(f"{path}: model file is empty")
        options = ort.SessionOptions()
        options.log_severity_level = 4  # onnxruntime's own error log line would be a second line on stderr
        if threads is None:
            threads = configured_threads()
        if threads:
            options.intra_op_num_threads = threads
            options.inter_op_num_threads = 1
        try:
            self.session = ort.InferenceSession(self.path, options, providers=["CPUExecutionProvider"])
        except Exception as error:  # onnxruntime's own error types: the file is not a model it can load
            raise InputError(f"{path}: not a loadable ONNX model ({type(error).__name__})") from None
        try:
            self.metadata = self.session.get_modelmeta().custom_metadata_map
            # names, types and shapes read here: onnxruntime decodes each when it is first read
            inputs = [(i.name, i.type, i.shape) for i in self.session.get_inputs()]
            outputs = [(o.name, o.shape) for o in self.session.get_outputs()]
        except UnicodeDecodeError:  # a damaged file: onnxruntime hands its strings over as UTF-8
            raise InputError(f"{path}: metadata or tensor names are not UTF-8 text; re-export the run") from None
        if "kind" not in self.metadata:
            raise InputError(f"{path}: not a Touchstone model (no metadata key 'kind')")
        self.kind = self.metadata["kind"]
        if self.kind not in KINDS:
            raise InputError(f"{path}: metadata 'kind' must be one of {', '.join(KINDS)}, got {self.kind[:40]!r}")
        self.channels = self._names("channels")
        self.outputs = self._names("outputs")
        if self.kind == "regression":
            self.targets = self._names("targets")
            self.input_shape = (len(self.channels),)
            self.output_width = len(self.targets)
        else:
            self.classes = self._names("classes")
            self.window_steps = self._positive_integer("window_steps")
            self.input_shape = (len(self.channels), self.window_steps)
            self.output_width = len(self.classes)
        self._check_graph(inputs, outputs)

    # -- the file's metadata and graph ------------------------------------------------------
    def _value(self, key) -> str:
        if key not in self.metadata:
            raise InputError(f"{self.path}: metadata key '{key}' is missing (a {self.kind} model needs it); "
                             "re-export the run")
        return self.metadata[key]

    def _names(self, key) -> list[str]:
        """A metadata value that must be a JSON list of distinct names."""
        text = self._value(key)
        try:
            names = json.loads(text)
        except ValueError:
            raise InputError(f"{self.path}: metadata '{key}' is not valid JSON: {text[:60]!r}") from None
        if not (isinstance(names, list) and names and all(isinstance(name, str) for name in names)):
            raise InputError(f"{self.path}: metadata '{key}' must be a non-empty JSON list of names, got {text[:60]!r}")
        twice = sorted({name for name in names if names.count(name) > 1})
        if twice:
            raise InputError(f"{self.path}: metadata '{key}' lists {twice[0][:40]!r} more than once")
        return names

    def _positive_integer(self, key) -> int:
        text = self._value(key)
        if not (text.isascii() and text.isdigit() and int(text) > 0):
            raise InputError(f"{self.path}: metadata '{key}' must be a positive whole number, got {text[:40]!r}")
        return int(text)

    def _check_graph(self, inputs, outputs) -> None:
        """The graph takes and returns what its metadata says, so a mismatch is found here, not as
        an onnxruntime error halfway through a prediction. inputs: (name, type, shape) each;
        outputs: (name, shape) each."""
        name = INPUT_NAME[self.kind]
        if [i[0] for i in inputs] != [name]:
            raise InputError(f"{self.path}: the graph takes {[i[0] for i in inputs]}, expected one input '{name}' "
                             f"for a {self.kind} model")
        _, kind, shape = inputs[0]
        if kind not in INPUT_DTYPES:
            raise InputError(f"{self.path}: the graph's input '{name}' is {kind}, expected a float tensor")
        self.input_dtype = np.dtype(INPUT_DTYPES[kind])
        if not _fits(shape, self.input_shape):
            raise InputError(f"{self.path}: the graph's input '{name}' has shape {shape}, but metadata "
                             f"'channels'{' and window_steps' if self.kind == 'classification' else ''} say "
                             f"(batch, {', '.join(map(str, self.input_shape))})")
        if [o[0] for o in outputs] != self.outputs or self.outputs[0] != MAIN_OUTPUT[self.kind]:
            raise InputError(f"{self.path}: metadata 'outputs' says {self.outputs} but the graph returns "
                             f"{[o[0] for o in outputs]}; a {self.kind} model's first output is "
                             f"'{MAIN_OUTPUT[self.kind]}'")
        named = "targets" if self.kind == "regression" else "classes"
        for output, shape in outputs:
            if not _fits(shape, (self.output_width,)):
                raise InputError(f"{self.path}: the graph's output '{output}' has shape {shape}, "
                                 f"but metadata '{named}' names {self.output_width}")

    # -- running the graph ------------------------------------------------------------------
    def _model_input(self, values: np.ndarray, locate) -> np.ndarray:
        """`values` in the graph's input dtype. A value that is not finite there (NaN, inf, or a
        finite float64 beyond float32's range, which the cast turns into inf) is an InputError
        naming where it is: `locate(index)`."""
        if values.dtype.kind not in "iuf":
            raise InputError(f"{self.path}: input values must be real numbers, got dtype {values.dtype}")
        with np.errstate(over="ignore", invalid="ignore"):
            cast = values.astype(self.input_dtype)
        bad = ~np.isfinite(cast)
        if bad.any():
            index = tuple(int(i) for i in np.argwhere(bad)[0])
            value = values[index]
            largest = np.finfo(self.input_dtype).max
            problem = (f"{value:g}, beyond the model's {self.input_dtype.name} range (±{largest:.4g})"
                       if np.isfinite(value) else f"{value} (not finite)")
            raise InputError(f"{locate(index)} has {problem}")
        return cast

    def _run(self, values: np.ndarray, locate) -> dict[str, np.ndarray]:
        """The graph's outputs by name, each (n, width) and finite; `locate(row)` names an input row."""
        try:
            results = self.session.run(None, {INPUT_NAME[self.kind]: values})
        except Exception as error:  # onnxruntime's own error types: a graph that cannot run this input
            message = str(error).strip().splitlines()[0][:200] if str(error).strip() else ""
            raise InputError(f"{self.path}: the model failed to run ({type(error).__name__}: {message})") from None
        out = {}
        for name, result in zip(self.outputs, results):
            result = np.asarray(result)
            if result.shape != (len(values), self.output_width):
                raise InputError(f"{self.path}: output '{name}' has shape {result.shape}, expected "
                                 f"({len(values)}, {self.output_width})")
            finite = np.isfinite(result).all(axis=1)
            if not finite.all():
                raise InputError(f"{locate(int(np.argmin(finite)))}: the model's output '{name}' is not finite "
                                 "(NaN or inf); the input is outside what the model can compute")
            out[name] = result
        return out

    def _cell(self, source):
        """Names a (row, channel) cell of a table as a user finds it in the file."""
        return lambda index: f"{source}: channel column '{self.channels[index[1]]}', {where(source, index[0])}"

    # -- regression -------------------------------------------------------------------------
    def predict_array(self, readings: np.ndarray) -> dict[str, np.ndarray]:
        readings = np.asarray(readings)
        if readings.ndim != 2 or readings.shape[1] != len(self.channels):
            raise InputError(f"{self.path}: expected readings of shape (n, {len(self.channels)}), got {readings.shape}")
        values = self._model_input(readings, lambda i: f"readings[{i[0]}, {i[1]}] (channel '{self.channels[i[1]]}')")
        return self._run(values, lambda row: f"readings row {row}")

    def predict_table(self, frame: pd.DataFrame, source: str = "input") -> pd.DataFrame:
        check_numeric_columns(frame, self.channels, "channel", source)
        readings = frame[self.channels].to_numpy(dtype=np.float64)
        out = self._run(self._model_input(readings, self._cell(source)), lambda row: f"{source}: {where(source, row)}")
        prediction = out["prediction"].astype(np.float64)  # bounds in float64: float32 sums could overflow
        result = pd.DataFrame(prediction, columns=self.targets)
        if "interval_half_width" in out:
            half = out["interval_half_width"].astype(np.float64)
            for k, target in enumerate(self.targets):
                result[f"{target}_lower95"] = prediction[:, k] - half[:, k]
                result[f"{target}_upper95"] = prediction[:, k] + half[:, k]
        return result

    # -- classification ---------------------------------------------------------------------
    def predict_windows(self, windows: np.ndarray) -> np.ndarray:
        windows = np.asarray(windows)
        if windows.ndim != 3 or windows.shape[1:] != self.input_shape:
            raise InputError(f"{self.path}: expected windows of shape (n, {self.input_shape[0]}, "
                             f"{self.input_shape[1]}), got {windows.shape}")
        values = self._model_input(windows, lambda i: f"windows[{i[0]}, {i[1]}, {i[2]}] (channel "
                                                      f"'{self.channels[i[1]]}')")
        return self._run(values, lambda row: f"window {row}")["probabilities"]

    def predict_recording(self, frame: pd.DataFrame, source: str = "input") -> pd.DataFrame:
        """Cut one recording (rows = time steps, channel columns) into consecutive windows."""
        check_numeric_columns(frame, self.channels, "channel", source)
        signal = self._model_input(frame[self.channels].to_numpy(dtype=np.float64), self._cell(source))
        steps = self.window_steps
        n = len(signal) // steps
        if n == 0:
            raise InputError(f"{source}: {len(signal)} rows is shorter than the model's window of {steps} steps")
        windows = np.ascontiguousarray(signal[:n * steps].reshape(n, steps, len(self.channels)).transpose(0, 2, 1))
        window = lambda k: f"{source}: the window starting at {where(source, k * steps)}"  # noqa: E731
        proba = self._run(windows, window)["probabilities"]
        result = pd.DataFrame(proba, columns=[f"p_{c}" for c in self.classes])
        result.insert(0, "predicted", np.asarray(self.classes)[proba.argmax(axis=1)])
        result.insert(0, "start_row", np.arange(n) * steps)
        return result


def _fits(shape, expected) -> bool:
    """A graph's (batch, ...) shape against the expected trailing dims; a named (dynamic) dim fits any."""
    return len(shape) == len(expected) + 1 and all(not isinstance(d, int) or d == e
                                                   for d, e in zip(shape[1:], expected))
