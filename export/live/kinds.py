"""What one kind of exported model does with a stream's readings: one prediction per line (a table
model), per hop of a sliding window (a recordings model), or per frame (the contact tracker).

Each takes parsed lines (number, time_s or None, readings) and returns output rows (number,
time_s, values or a reason the line's prediction is refused); the model's own time per call goes
to `model_time` (export/live/summary.py's ModelTime). Values are the columns a batch predict.py writes
(export/onnx_predictor.py's Kind.columns), so a stream and a file give the same numbers.
"""
from collections import deque

import numpy as np

from common.errors import InputError
from export.window_force import window_force
from models.contact_tracking import ContactTracker

RATE_TOLERANCE = 0.01  # relative, as predict.py allows for a file's time column


class RowStream:
    """A table model: every line is one press, predicted on its own (or with the lines waiting)."""
    unit = "lines"
    holds_lists = False   # an output row is plain values

    def __init__(self, predictor):
        self.predictor = predictor
        self.input_columns = predictor.channels
        self.columns = predictor.reads.columns(predictor)

    def predict(self, lines, model_time) -> list:
        p = self.predictor
        values = np.array([readings for _, _, readings in lines], dtype=p.input_dtype)
        return _rows(p, lines, values, model_time)

    def gap(self) -> None:
        """Lines were dropped: a row model has no state to reset."""


class WindowStream:
    """A recordings model over a sliding window of its own length: a prediction every `hop` lines
    once the window is full (hop = the window: back-to-back windows, as predict.py cuts a file).
    The window lives in a ring written twice (steps k and k + W), so the newest W steps are
    always one contiguous slice and nothing is shifted per line."""
    unit = "lines"
    holds_lists = False

    def __init__(self, predictor, hop: int | None = None):
        self.predictor = predictor
        self.steps = predictor.window_steps
        self.hop = self.steps if hop is None else hop
        if not 1 <= self.hop:
            raise InputError(f"hop must be a positive whole number of steps, got {self.hop}")
        self.input_columns = predictor.channels
        self.columns = ["start_line"] + predictor.reads.columns(predictor)
        self.ring = np.zeros((len(self.input_columns), 2 * self.steps), dtype=predictor.input_dtype)
        self.numbers = np.zeros(2 * self.steps, dtype=np.int64)
        self.stamps = deque(maxlen=self.steps)
        self.rate_checked = predictor.sample_rate_hz is None
        self.gap()

    def gap(self) -> None:
        """Start the window again (lines were dropped: a window never spans a gap)."""
        self.filled, self.position = 0, 0
        self.stamps.clear()

    def push(self, number: int, stamp, readings) -> np.ndarray | None:
        """Add one step; the window (channels, steps) when this step completes a hop, else None."""
        k, w = self.position, self.steps
        self.ring[:, k] = self.ring[:, k + w] = readings
        self.numbers[k] = self.numbers[k + w] = number
        self.position, self.filled = (k + 1) % w, self.filled + 1
        if stamp is not None:
            self.stamps.append(stamp)
        if self.filled < w or (self.filled - w) % self.hop:
            return None
        if not self.rate_checked and len(self.stamps) == w:
            self._check_rate()
        return self.ring[:, self.position:self.position + w]

    def _check_rate(self) -> None:
        steps = np.diff(np.asarray(self.stamps))
        rate, model_rate = 1 / np.median(steps) if np.median(steps) > 0 else np.inf, self.predictor.sample_rate_hz
        if abs(rate / model_rate - 1) > RATE_TOLERANCE:
            raise InputError(f"the stream's time stamps give {rate:g} Hz, but the model's windows are {model_rate:g} "
                             f"Hz; stream at {model_rate:g} Hz")
        self.rate_checked = True

    def predict(self, lines, model_time) -> list:
        windows, done = [], []
        for number, stamp, readings in lines:
            window = self.push(number, stamp, readings)
            if window is not None:
                windows.append(window.copy())
                done.append((number, stamp, int(self.numbers[self.position])))
        if not windows:
            return []
        rows = _rows(self.predictor, done, np.stack(windows), model_time)
        return [(number, stamp, values if isinstance(values, str) else [start] + values)
                for (number, stamp, values), (_, _, start) in zip(rows, done)]


class TrackerStream:
    """The contact tracker, frame by frame: the first `n_rest_frames` lines are its baseline (no
    contact), then every frame gives its contacts with stable ids; force per contact from the
    exported force model, which reads the 3 x 3 window around a contact's peak."""
    unit = "frames"
    columns = ["contacts", "id", "x_mm", "y_mm", "force_n"]
    holds_lists = True    # a frame's contacts: a list per column

    def __init__(self, predictor, rows: int, cols: int, pitch_mm: float, n_rest_frames: int):
        force = window_force(predictor, "predict.py rows=/cols= (contact tracking)", checked=False)
        self.tracker = ContactTracker(rows=rows, cols=cols, pitch_mm=pitch_mm, force_model=force,
                                      force_feature="window")
        self.grid = (rows, cols)
        self.n_rest_frames = n_rest_frames
        self.rest = []
        self.input_columns = [f"cell_r{r}_c{c}" for r in range(rows) for c in range(cols)]

    def gap(self) -> None:
        """Frames were dropped: the tracks carry on (a contact unseen for a few frames keeps its id)."""

    def predict(self, lines, model_time) -> list:
        out = []
        for number, stamp, readings in lines:
            frame = readings.reshape(self.grid)
            if len(self.rest) < self.n_rest_frames:
                self.rest.append(frame)
                if len(self.rest) == self.n_rest_frames:
                    self.tracker.fit(np.stack(self.rest))
                continue
            contacts = model_time.call(self.tracker.update, frame)
            force = contacts.force_n
            if not np.isfinite(force).all():
                out.append((number, stamp, "the force model's output is not finite"))
                continue
            out.append((number, stamp, [len(contacts.ids), contacts.ids.tolist(), np.round(contacts.x_mm, 3).tolist(),
                                        np.round(contacts.y_mm, 3).tolist(), np.round(force, 4).tolist()]))
        return out


def _rows(predictor, lines, values, model_time) -> list:
    """One model call for the stacked inputs: an output row per line, or why it is refused."""
    raw = model_time.call(predictor.run_graph, values)
    out = dict(zip(predictor.outputs, raw))
    arrays = predictor.reads.arrays(predictor, out)
    rows = zip(*[a.tolist() for a in arrays])
    if all(np.isfinite(r).all() for r in raw):   # the usual case, without a per-row pass
        return [(number, stamp, list(row)) for (number, stamp, _), row in zip(lines, rows)]
    finite = np.logical_and.reduce([np.isfinite(r).reshape(len(r), -1).all(axis=1) for r in raw])
    return [(number, stamp, list(row) if ok else "the model's output is not finite (NaN or inf)")
            for (number, stamp, _), row, ok in zip(lines, rows, finite)]
