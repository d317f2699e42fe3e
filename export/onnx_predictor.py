"""Run an exported Touchstone model with onnxruntime, checking inputs against its metadata.

    predictor = OnnxPredictor("run/model.onnx")
    predictor.predict_table(frame)            # a row model: a frame with the model's channel columns
    predictor.predict_windows(windows)        # a window model: (n, channels, steps) raw windows
    predictor.predict_recordings(recordings)  # a window model: whole recordings, cut into windows
A model reads rows (metadata input 'channels': a regression, or a classifier of table rows) or
windows of a recording (input 'window': a time-series classifier, `window_steps` raw steps at
`sample_rate_hz`, or 'unknown' when the data did not say).
Every problem with the model file, its metadata or the input is a one-line InputError naming the
file and the key, column or row; a value that is not finite in the graph's input dtype (1e308 in
a float32 graph) is refused before the model runs, and an output that is not finite (an input
outside what the model can compute) is refused before anything is returned.
"""
import json
import math
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import onnxruntime as ort
import pandas as pd

from common.errors import InputError
from common.threads import configured_threads
from data.readers.table_reader import check_numeric_columns, where
from data.units import clip_columns

INPUT_DTYPES = {"tensor(double)": np.float64, "tensor(float)": np.float32}


@dataclass(frozen=True)
class Kind:
    """What a kind of model (metadata 'kind', written by export/pipelines.py) reads and writes: the
    metadata key naming its output columns, the graph inputs it may read (metadata 'input'; the
    default when a file has none) and its first output. A regression reads rows; a classifier
    rows or windows."""
    labels: str
    inputs: tuple[str, ...]
    default_input: str
    main_output: str

    def columns(self, predictor) -> list[str]:
        """The output columns of one prediction, in order (a table's and a stream's)."""
        raise NotImplementedError

    def arrays(self, predictor, out: dict) -> list[np.ndarray]:
        """The graph's outputs for n inputs as one array of n values per output column."""
        raise NotImplementedError

    def table(self, predictor, out: dict) -> pd.DataFrame:
        """One output row per input row of a table."""
        return pd.DataFrame(dict(zip(self.columns(predictor), self.arrays(predictor, out))))

    def outputs(self, predictor, with_unit) -> list[str]:
        """What the model writes, for --help (`with_unit` names a column with its unit)."""
        raise NotImplementedError


class Regression(Kind):
    def columns(self, predictor):
        """The targets, then each target's 95 % bounds when the model has them."""
        bounds = [f"{t}_{side}95" for t in predictor.targets for side in ("lower", "upper")]
        return predictor.targets + (bounds if "interval_half_width" in predictor.outputs else [])

    def arrays(self, predictor, out):
        targets = predictor.targets
        prediction = out["prediction"].astype(np.float64)  # bounds in float64: float32 sums could overflow
        # predictions and bounds within each target's physical range (data/units.py), as the run reports
        # them: the ranges read once per model (a stream clips every line; reading the names each time
        # cost 17 µs a line), clipped as clip_columns clips (no rule: -inf, inf)
        if predictor.target_range is None:
            low_high = clip_columns(np.array([[-np.inf] * len(targets), [np.inf] * len(targets)]), targets)
            predictor.target_range = (low_high[0], low_high[1])
        low, high = predictor.target_range

        def clip(values):   # np.clip's own wrapper costs a stream 2 µs a call; the same two ufuncs bare
            return np.minimum(np.maximum(values, low), high)
        arrays = list(clip(prediction).T)
        if "interval_half_width" in out:
            half = out["interval_half_width"].astype(np.float64)
            lower, upper = clip(prediction - half), clip(prediction + half)
            arrays += [bound[:, k] for k in range(len(targets)) for bound in (lower, upper)]
        return arrays

    def outputs(self, predictor, with_unit):
        bounds = len(predictor.outputs) > 1
        return ["  output: " + ", ".join(with_unit(t) for t in predictor.targets)
                + (", each with _lower95 and _upper95" if bounds else "")]


class Classification(Kind):
    def columns(self, predictor):
        """The predicted class and one probability column per class."""
        return ["predicted"] + [f"p_{c}" for c in predictor.classes]

    def arrays(self, predictor, out):
        proba = out["probabilities"]
        return [np.asarray(predictor.classes)[proba.argmax(axis=1)]] + list(proba.T)

    def outputs(self, predictor, with_unit):
        label = predictor.metadata.get("label")  # the target column a table classifier was trained on
        return [f"  classes{f' of {label!r}' if label else ''} ({len(predictor.classes)}): "
                f"{', '.join(predictor.classes)}",
                "  output: " + ("recording (when the input names them), start_step, " if predictor.reads_windows
                                else "") + "predicted, " + ", ".join(f"p_{c}" for c in predictor.classes)]


KINDS = {"regression": Regression("targets", ("channels",), "channels", "prediction"),
         "classification": Classification("classes", ("channels", "window"), "window", "probabilities")}


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
        self.reads = KINDS[self.kind]
        self.target_range = None   # a regression's (low, high) per target, read on its first prediction
        self.channels = self._names("channels")
        self.outputs = self._names("outputs")
        labels = self._names(self.reads.labels)
        setattr(self, self.reads.labels, labels)   # self.targets or self.classes
        self.output_width = len(labels)
        self.input_name = self.metadata.get("input", self.reads.default_input)
        if self.input_name not in self.reads.inputs:
            raise InputError(f"{self.path}: metadata 'input' must be {' or '.join(map(repr, self.reads.inputs))} "
                             f"for a {self.kind} model, got {self.input_name[:40]!r}")
        self.reads_windows = self.input_name == "window"
        if self.reads_windows:
            self.window_steps = self._positive_integer("window_steps")
            self.sample_rate_hz = self._sample_rate()
            self.input_shape = (len(self.channels), self.window_steps)
        else:
            self.input_shape = (len(self.channels),)
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

    def _sample_rate(self) -> float | None:
        """The raw windows' rate in hertz; None where the data did not say ('unknown' or no key)."""
        text = self.metadata.get("sample_rate_hz", "unknown")
        try:
            rate = None if text == "unknown" else float(text)
        except ValueError:
            rate = math.nan
        if rate is not None and not (math.isfinite(rate) and rate > 0):
            raise InputError(f"{self.path}: metadata 'sample_rate_hz' must be a positive number of hertz or "
                             f"'unknown', got {text[:40]!r}")
        return rate

    def _check_graph(self, inputs, outputs) -> None:
        """The graph takes and returns what its metadata says, so a mismatch is found here, not as
        an onnxruntime error halfway through a prediction. inputs: (name, type, shape) each;
        outputs: (name, shape) each."""
        name = self.input_name
        if [i[0] for i in inputs] != [name]:
            raise InputError(f"{self.path}: the graph takes {[i[0] for i in inputs]}, expected one input '{name}' "
                             f"for a {self.kind} model")
        _, kind, shape = inputs[0]
        if kind not in INPUT_DTYPES:
            raise InputError(f"{self.path}: the graph's input '{name}' is {kind}, expected a float tensor")
        self.input_dtype = np.dtype(INPUT_DTYPES[kind])
        if not _fits(shape, self.input_shape):
            raise InputError(f"{self.path}: the graph's input '{name}' has shape {shape}, but metadata "
                             f"'channels'{' and window_steps' if self.reads_windows else ''} say "
                             f"(batch, {', '.join(map(str, self.input_shape))})")
        if [o[0] for o in outputs] != self.outputs or self.outputs[0] != self.reads.main_output:
            raise InputError(f"{self.path}: metadata 'outputs' says {self.outputs} but the graph returns "
                             f"{[o[0] for o in outputs]}; a {self.kind} model's first output is "
                             f"'{self.reads.main_output}'")
        for output, shape in outputs:
            if not _fits(shape, (self.output_width,)):
                raise InputError(f"{self.path}: the graph's output '{output}' has shape {shape}, "
                                 f"but metadata '{self.reads.labels}' names {self.output_width}")

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

    def run_graph(self, values: np.ndarray) -> list[np.ndarray]:
        """The graph's raw outputs for values already in its input dtype and shape, unchecked: the
        live loop (export/live/) checks each line itself and cannot afford a second pass."""
        return self.session.run(None, {self.input_name: values})

    def _run(self, values: np.ndarray, locate) -> dict[str, np.ndarray]:
        """The graph's outputs by name, each (n, width) and finite; `locate(row)` names an input row."""
        try:
            results = self.run_graph(values)
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

    def _require(self, windows: bool, what: str) -> None:
        if self.reads_windows != windows:
            reads = (f"windows of {self.window_steps} steps of a recording" if self.reads_windows
                     else "one row per press")
            raise InputError(f"{self.path}: this {self.kind} model reads {reads}, not {what}")

    # -- rows: a regression, or a classifier of table rows ------------------------------------
    def predict_array(self, readings: np.ndarray) -> dict[str, np.ndarray]:
        self._require(windows=False, what="readings of shape (n, channels)")
        readings = np.asarray(readings)
        if readings.ndim != 2 or readings.shape[1] != len(self.channels):
            raise InputError(f"{self.path}: expected readings of shape (n, {len(self.channels)}), got {readings.shape}")
        values = self._model_input(readings, lambda i: f"readings[{i[0]}, {i[1]}] (channel '{self.channels[i[1]]}')")
        return self._run(values, lambda row: f"readings row {row}")

    def predict_table(self, frame: pd.DataFrame, source: str = "input") -> pd.DataFrame:
        """One output row per input row: the targets (and their 95 % bounds when the model has
        them), or the predicted class and one probability column per class."""
        self._require(windows=False, what="a table of rows")
        check_numeric_columns(frame, self.channels, "channel", source)
        readings = frame[self.channels].to_numpy(dtype=np.float64)
        out = self._run(self._model_input(readings, self._cell(source)), lambda row: f"{source}: {where(source, row)}")
        return self.reads.table(self, out)

    # -- windows of recordings: a time-series classifier --------------------------------------
    def predict_windows(self, windows: np.ndarray) -> np.ndarray:
        self._require(windows=True, what="windows of shape (n, channels, steps)")
        windows = np.asarray(windows)
        if windows.ndim != 3 or windows.shape[1:] != self.input_shape:
            raise InputError(f"{self.path}: expected windows of shape (n, {self.input_shape[0]}, "
                             f"{self.input_shape[1]}), got {windows.shape}")
        values = self._model_input(windows, lambda i: f"windows[{i[0]}, {i[1]}, {i[2]}] (channel "
                                                      f"'{self.channels[i[1]]}')")
        return self._run(values, lambda row: f"window {row}")["probabilities"]

    def predict_recordings(self, recordings: list["Recording"], source: str = "input",
                           id_column: str = "recording") -> pd.DataFrame:
        """Each recording cut into back-to-back windows of window_steps from its first step (the
        steps after its last whole window are not predicted): one row per window with the
        recording's id in `id_column` (left out when the recordings have no ids), the step the
        window starts at, the predicted class and one probability column per class."""
        self._require(windows=True, what="recordings")
        steps = self.window_steps
        windows, starts = [], []  # starts: (recording, step) per window
        for recording in recordings:
            name = f"recording {recording.id}, " if recording.id is not None else ""
            values = np.asarray(recording.values)
            if values.ndim != 2 or values.shape[0] != len(self.channels):
                raise InputError(f"{source}: {name}expected ({len(self.channels)} channels, steps), got {values.shape}")
            n = values.shape[1] // steps
            if n == 0:
                raise InputError(f"{source}: {name}{values.shape[1]} steps is shorter than the model's window of "
                                 f"{steps} steps")
            cast = self._model_input(values, lambda i: f"{source}: {name}channel '{self.channels[i[0]]}', "
                                                       f"{recording.place(i[1])}")
            windows.append(cast[:, :n * steps].reshape(len(self.channels), n, steps).transpose(1, 0, 2))
            starts += [(recording, k * steps) for k in range(n)]

        def window(row):
            recording, start = starts[row]
            name = f"recording {recording.id}, " if recording.id is not None else ""
            return f"{source}: {name}the window starting at {recording.place(start)}"
        proba = self._run(np.ascontiguousarray(np.concatenate(windows)), window)["probabilities"]
        result = self._classes_frame(proba)
        result.insert(0, "start_step", [start for _, start in starts])
        if any(recording.id is not None for recording in recordings):
            result.insert(0, id_column, [recording.id for recording, _ in starts])
        return result

    def _classes_frame(self, proba: np.ndarray) -> pd.DataFrame:
        return self.reads.table(self, {"probabilities": proba})


@dataclass(frozen=True)
class Recording:
    """One recording for predict_recordings: its id (None for a file that is one unnamed
    recording), its values (channels in the model's order, steps) and where step k sits in the
    file, for messages (`place(k)`: 'line 12' of a CSV, 'step 40' of an NPZ recording)."""
    id: Hashable | None
    values: np.ndarray
    place: Callable[[int], str]


def _fits(shape, expected) -> bool:
    """A graph's (batch, ...) shape against the expected trailing dims; a named (dynamic) dim fits any."""
    return len(shape) == len(expected) + 1 and all(not isinstance(d, int) or d == e
                                                   for d, e in zip(shape[1:], expected))
