"""Run an exported Touchstone model with onnxruntime, checking inputs against its metadata.

    predictor = OnnxPredictor("run/model.onnx")
    predictor.predict_table(frame)      # regression: a frame with the model's channel columns
    predictor.predict_windows(windows)  # classification: (n, channels, steps) raw windows
Every problem with the input is a one-line InputError.
"""
import json

import numpy as np
import onnxruntime as ort
import pandas as pd

from data.errors import InputError
from data.table_files import check_numeric_columns
from data.threads import configured_threads


class OnnxPredictor:
    def __init__(self, path, threads: int | None = None):
        """threads: intra-op threads; None = the Touchstone setting in force (data/threads.py),
        0 = onnxruntime's own default (one per core)."""
        options = ort.SessionOptions()
        if threads is None:
            threads = configured_threads()
        if threads:
            options.intra_op_num_threads = threads
            options.inter_op_num_threads = 1
        try:
            self.session = ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
        except Exception as error:
            raise InputError(f"{path}: not a loadable ONNX model ({type(error).__name__})") from None
        meta = self.session.get_modelmeta().custom_metadata_map
        if "kind" not in meta:
            raise InputError(f"{path}: not a Touchstone model (no metadata)")
        self.path = str(path)
        self.metadata = meta
        self.kind = meta["kind"]
        self.channels = json.loads(meta["channels"])
        self.outputs = json.loads(meta["outputs"])

    # -- regression -------------------------------------------------------------------------
    @property
    def targets(self) -> list[str]:
        return json.loads(self.metadata["targets"])

    def predict_array(self, readings: np.ndarray) -> dict[str, np.ndarray]:
        readings = np.asarray(readings)
        if readings.ndim != 2 or readings.shape[1] != len(self.channels):
            raise InputError(f"{self.path}: expected readings of shape (n, {len(self.channels)}), got {readings.shape}")
        if not np.issubdtype(readings.dtype, np.number):
            raise InputError(f"{self.path}: readings must be numeric, got dtype {readings.dtype}")
        if not np.isfinite(readings).all():
            raise InputError(f"{self.path}: readings contain NaN or inf")
        values = self.session.run(None, {"channels": readings.astype(np.float64)})
        return dict(zip(self.outputs, values))

    def predict_table(self, frame: pd.DataFrame, source: str = "input") -> pd.DataFrame:
        check_numeric_columns(frame, self.channels, "channel", source)
        out = self.predict_array(frame[self.channels].to_numpy(dtype=np.float64))
        result = pd.DataFrame(out["prediction"], columns=self.targets)
        if "interval_half_width" in out:
            for k, target in enumerate(self.targets):
                result[f"{target}_lower95"] = out["prediction"][:, k] - out["interval_half_width"][:, k]
                result[f"{target}_upper95"] = out["prediction"][:, k] + out["interval_half_width"][:, k]
        return result

    # -- classification ---------------------------------------------------------------------
    @property
    def classes(self) -> list[str]:
        return json.loads(self.metadata["classes"])

    @property
    def window_steps(self) -> int:
        return int(self.metadata["window_steps"])

    def predict_windows(self, windows: np.ndarray) -> np.ndarray:
        windows = np.asarray(windows)
        expected = (len(self.channels), self.window_steps)
        if windows.ndim != 3 or windows.shape[1:] != expected:
            raise InputError(f"{self.path}: expected windows of shape (n, {expected[0]}, {expected[1]}), "
                             f"got {windows.shape}")
        if not np.issubdtype(windows.dtype, np.number) or not np.isfinite(windows).all():
            raise InputError(f"{self.path}: windows must be finite numbers")
        return self.session.run(None, {"window": windows.astype(np.float32)})[0]

    def predict_recording(self, frame: pd.DataFrame, source: str = "input") -> pd.DataFrame:
        """Cut one recording (rows = time steps, channel columns) into consecutive windows."""
        check_numeric_columns(frame, self.channels, "channel", source)
        signal = frame[self.channels].to_numpy(dtype=np.float64).T
        n = signal.shape[1] // self.window_steps
        if n == 0:
            raise InputError(f"{source}: {signal.shape[1]} rows is shorter than the model's window of "
                             f"{self.window_steps} steps")
        windows = signal[:, :n * self.window_steps].reshape(len(self.channels), n, self.window_steps).transpose(1, 0, 2)
        proba = self.predict_windows(windows)
        result = pd.DataFrame(proba, columns=[f"p_{c}" for c in self.classes])
        result.insert(0, "predicted", np.asarray(self.classes)[proba.argmax(axis=1)])
        result.insert(0, "start_row", np.arange(n) * self.window_steps)
        return result
