"""One line of a live stream -> the sensor's readings: the one line format predict.py streams.

A line is comma-separated numbers, as a rig's firmware prints them over a serial port:

    [time_s,]c1,c2,...,cN

N values (the model's channels in its order, or a contact grid's cells row-major) or N + 1,
where the first is the rig's own time stamp in seconds. Blank lines and `#` comments are
skipped. A first line that is text is a CSV header: it names the columns, the model's channels
are picked from it by name (so `cat predictions.csv | predict.py input=-` reads what the batch
`predict.py` reads) and `time_s`, when present, is the time stamp.

A line that cannot be a reading raises BadLine with why (wrong count, text, NaN, a value beyond
float32 or outside its unit's physical range); the caller says which line and skips or stops.
"""
import math
import operator

import numpy as np

from data.readers.table_reader import MODEL_DTYPE_MAX, model_value_bounds

TIME_COLUMN = "time_s"


class BadLine(ValueError):
    """A line that is not a reading; the message says why, the caller adds where."""


class LineFormat:
    """Turns text lines into (time_s or None, readings float64 [n]). `columns`: the names of the
    readings in the model's order (a grid's cells get positional names and no unit)."""

    def __init__(self, columns: list[str]):
        self.columns = list(columns)
        self.width = len(self.columns)
        self.low, self.high = model_value_bounds(self.columns)
        self.low_list, self.high_list = self.low.tolist(), self.high.tolist()
        self.pick = None         # a header's column index per reading, once a header was read
        self.time_index = None   # the header's time stamp column
        self.header_width = None
        self.seen_data = False

    def header(self, fields: list[str]) -> None:
        """A text first line: the columns by name. Raises BadLine when it lacks a reading's column."""
        names = [field.strip() for field in fields]
        missing = [c for c in self.columns if c not in names]
        if missing:
            shown = ", ".join(missing[:5]) + (" ..." if len(missing) > 5 else "")
            raise BadLine(f"a header without the model's column(s) {shown}")
        self.pick = np.array([names.index(c) for c in self.columns])
        self.time_index = names.index(TIME_COLUMN) if TIME_COLUMN in names else None
        self.header_width = len(names)

    def parse(self, text: str) -> tuple[float | None, np.ndarray] | None:
        """One line's time stamp and readings; None for a blank or comment line (or the header)."""
        text = text.split("#", 1)[0].strip()
        if not text:
            return None
        fields = text.split(",")
        if not self.seen_data:   # only the first line may be a header
            self.seen_data = True
            try:
                _numbers(fields)
            except BadLine:
                self.header(fields)
                return None
        if self.pick is not None:  # only the header's reading and time columns need be numbers
            if len(fields) != self.header_width:
                raise BadLine(f"{len(fields)} values, expected {self.header_width} (the header's columns)")
            readings = _numbers([fields[k] for k in self.pick])
            stamp = None if self.time_index is None else _numbers([fields[self.time_index]])[0]
        else:
            values = _numbers(fields)
            if len(values) == self.width:
                stamp, readings = None, values
            elif len(values) == self.width + 1:
                stamp, readings = values[0], values[1:]
            else:
                raise BadLine(f"{len(values)} values, expected {self.width} readings or time_s and {self.width} "
                              "readings")
        if stamp is not None and not math.isfinite(stamp):
            raise BadLine(f"time stamp {stamp} is not a finite number of seconds")
        # on Python floats: a dozen comparisons cost less than one numpy call (the loop's per-line budget)
        if not (all(map(operator.le, self.low_list, readings)) and all(map(operator.le, readings, self.high_list))):
            k = next(k for k, value in enumerate(readings) if not self.low_list[k] <= value <= self.high_list[k])
            value = readings[k]    # NaN fails both comparisons
            why = ("not finite" if not math.isfinite(value) else
                   f"beyond float32 (±{MODEL_DTYPE_MAX:.4g})" if abs(value) > MODEL_DTYPE_MAX else
                   f"outside its physical range [{self.low[k]:g}, {self.high[k]:g}]")
            raise BadLine(f"column '{self.columns[k]}' is {value:g}, {why}")
        return stamp, np.array(readings)


def _numbers(fields: list[str]) -> list[float]:
    try:
        return [float(field) for field in fields]
    except ValueError:
        for field in fields:   # the first that is not a number, for the message
            try:
                float(field)
            except ValueError:
                raise BadLine(f"{field.strip()[:30]!r} is not a number") from None
        raise
