"""Streams of frames from a capacitive array: what the scene simulates and what a user recorded.

A ContactStream holds the frames as the board reports them, one [rows, cols] matrix of raw
mutual-capacitance counts ("RMC", seed 001 sec. 2.3) per frame, oldest first, plus what a
tracker needs to interpret them: the frame rate, the electrode pitch and how many frames at
the start are rest frames (no contact; the tracker discards the first few and learns its
baseline from the rest, seed 001 sec. 2.4.3). A simulated stream also carries its ground
truth, one row per frame and contact; a user's recording has none (`truth` is None).

`load_frames` reads a user's recording: a CSV with one row per frame and rows x cols
comma-separated cell values in row-major order, as the firmware streams them (seed 001
eq. 2-3: x_11, x_12, ..., x_1m, x_21, ..., x_nm), or an NPY array [n_frames, rows, cols]
(or [n_frames, rows * cols]). Every problem is one line naming the file and what is wrong; a
cell must be a finite number within float32's range (the force model reads contacts' windows in
float32, where 1e308 is infinite, and the tracker's baseline spread of such counts overflows).
"""
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from common.errors import InputError
from data.readers.table_reader import MODEL_DTYPE_MAX

TRUTH_COLUMNS = ["frame", "contact_id", "x_mm", "y_mm", "force_n", "radius_mm", "session"]
WITHIN = f"cells must be finite numbers within float32 (±{MODEL_DTYPE_MAX:.4g})"


@dataclass
class ContactStream:
    frames: np.ndarray                  # [n_frames, rows, cols] float64, raw counts as the board reports
    frame_rate_hz: float
    pitch_mm: float                     # centre-to-centre distance of neighbouring crossings
    n_rest_frames: int                  # leading frames without contact (for the baseline)
    truth: pd.DataFrame | None = None   # TRUTH_COLUMNS, one row per (frame, contact); None: unknown
    description: dict = field(default_factory=dict)

    @property
    def rows(self) -> int:
        return int(self.frames.shape[1])

    @property
    def cols(self) -> int:
        return int(self.frames.shape[2])

    @property
    def n_frames(self) -> int:
        return int(self.frames.shape[0])

    def cell_centres_mm(self) -> tuple[np.ndarray, np.ndarray]:
        """x (along columns) and y (along rows) of every crossing's centre, each [rows, cols];
        cell (r, c) sits at ((c + 0.5) pitch, (r + 0.5) pitch)."""
        y, x = np.meshgrid((np.arange(self.rows) + 0.5) * self.pitch_mm,
                           (np.arange(self.cols) + 0.5) * self.pitch_mm, indexing="ij")
        return x, y


def _read_csv_frames(path: Path, n_cells: int) -> np.ndarray:
    try:
        frame = pd.read_csv(path, header=None, dtype=str, skipinitialspace=True, keep_default_na=False, na_values=[""],
                            skip_blank_lines=True, comment="#")
    except pd.errors.EmptyDataError:
        raise InputError(f"{path}: file is empty") from None
    except UnicodeDecodeError:  # a binary file given as CSV (a pickle, an image): refused, never decoded
        raise InputError(f"{path}: not a text file (bytes that are not UTF-8); expected one frame per line") from None
    except pd.errors.ParserError as error:
        # the C parser reports a row with more fields than the first as "Expected k fields in line n"
        raise InputError(f"{path}: rows differ in their number of cells "
                         f"({str(error).strip().splitlines()[-1]}); expected {n_cells} per frame") from None
    if frame.empty:
        raise InputError(f"{path}: file has no frames")
    if frame.shape[1] != n_cells:
        raise InputError(f"{path}: {frame.shape[1]} cells per frame, expected rows x cols = {n_cells}")
    text = frame.to_numpy(dtype=object)
    missing = pd.isna(text)
    if missing.any():
        row, col = map(int, np.argwhere(missing)[0])
        raise InputError(f"{path}: frame {row} has {n_cells - int((~missing[row]).sum())} missing cell(s) "
                         f"(first at cell {col}); expected {n_cells} per frame")
    values = frame.apply(pd.to_numeric, errors="coerce").to_numpy(dtype=np.float64)
    bad = _unusable(values)
    if bad.any():
        row, col = map(int, np.argwhere(bad)[0])
        raise InputError(f"{path}: frame {row}, cell {col} is not a finite number: {text[row, col]!r}; {WITHIN}")
    return values


def _read_npy_frames(path: Path, rows: int, cols: int) -> np.ndarray:
    try:
        values = np.load(path, allow_pickle=False)
    except Exception as error:  # a truncated or foreign file: name the file and the cause
        raise InputError(f"{path}: cannot read NPY array ({type(error).__name__}: {error})".splitlines()[0]) from None
    if values.dtype.kind not in "iuf":
        raise InputError(f"{path}: array of {values.dtype} values, expected numbers")
    if values.size == 0:
        raise InputError(f"{path}: array has no frames")
    if values.ndim == 3 and values.shape[1:] != (rows, cols):
        raise InputError(f"{path}: frames of {values.shape[1]} x {values.shape[2]} cells do not match the "
                         f"grid {rows} x {cols}")
    if values.ndim == 2 and values.shape[1] != rows * cols:
        raise InputError(f"{path}: {values.shape[1]} cells per frame, expected rows x cols = {rows * cols}")
    if values.ndim not in (2, 3):
        raise InputError(f"{path}: array of shape {values.shape}, expected [frames, rows, cols] "
                         "or [frames, rows * cols]")
    values = values.reshape(len(values), rows * cols).astype(np.float64)
    bad = _unusable(values)
    if bad.any():
        row, col = map(int, np.argwhere(bad)[0])
        raise InputError(f"{path}: frame {row}, cell {col} is not a finite number ({values[row, col]:g}); {WITHIN}")
    return values


def _unusable(values: np.ndarray) -> np.ndarray:
    """Cells that are NaN, infinite or beyond float32's range (MODEL_DTYPE_MAX)."""
    with np.errstate(invalid="ignore"):
        return ~(np.abs(values) <= MODEL_DTYPE_MAX)


def check_grid(rows, cols, pitch_mm, frame_rate_hz, source="stream") -> None:
    if not (isinstance(rows, (int, np.integer)) and isinstance(cols, (int, np.integer)) and rows >= 1 and cols >= 1):
        raise InputError(f"{source}: rows and cols must be positive integers, got {rows!r} x {cols!r}")
    if not (np.isfinite(pitch_mm) and pitch_mm > 0):
        raise InputError(f"{source}: pitch_mm must be a positive number, got {pitch_mm!r}")
    if not (np.isfinite(frame_rate_hz) and frame_rate_hz > 0):
        raise InputError(f"{source}: frame_rate_hz must be a positive number, got {frame_rate_hz!r}")


def load_frames(path: str | Path, rows: int, cols: int, pitch_mm: float = 10.0, frame_rate_hz: float = 60.0,
                n_rest_frames: int = 60, min_rest_frames: int = 10) -> ContactStream:
    """A user's recording as a ContactStream without ground truth.

    The first `n_rest_frames` frames must be free of contact; a file shorter than
    `min_rest_frames` (the fewest from which a per-cell mean and spread mean anything, after the
    tracker discards its first frames) is refused.
    """
    path = Path(path)
    check_grid(rows, cols, pitch_mm, frame_rate_hz, str(path))
    if not path.is_file():
        raise InputError(f"{path}: no such file")
    if path.stat().st_size == 0:
        raise InputError(f"{path}: file is empty")
    suffix = path.suffix.lower()
    if suffix == ".csv":
        values = _read_csv_frames(path, rows * cols)
    elif suffix == ".npy":
        values = _read_npy_frames(path, rows, cols)
    else:
        raise InputError(f"{path}: unsupported file type '{suffix}', expected .csv (one frame per row) or .npy")
    if not isinstance(n_rest_frames, (int, np.integer)) or n_rest_frames < min_rest_frames:
        raise InputError(f"{path}: n_rest_frames must be an integer >= {min_rest_frames}, got {n_rest_frames!r}")
    if len(values) < n_rest_frames:
        raise InputError(f"{path}: {len(values)} frames, fewer than the {n_rest_frames} rest frames needed "
                         "for a baseline")
    frames = values.reshape(len(values), rows, cols)
    return ContactStream(frames, float(frame_rate_hz), float(pitch_mm), int(n_rest_frames), None,
                         {"source": "file", "path": str(path)})


def frames_from_lines(lines, rows: int, cols: int, source: str = "stdin"):
    """Frames from text lines as the firmware streams them (one comma-separated row-major frame
    per line; blank lines and # comments skipped), one at a time: a serial port piped into
    standard input. A line with the wrong number of cells or a cell that is not a finite number
    is an InputError naming the line."""
    n_cells = rows * cols
    for number, line in enumerate(lines, start=1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        cells = text.split(",")
        if len(cells) != n_cells:
            raise InputError(f"{source}: line {number} has {len(cells)} cells, expected rows x cols = {n_cells}")
        try:
            frame = np.array([float(cell) for cell in cells])
        except ValueError:
            bad = next(c for c in cells if not _is_number(c))
            raise InputError(f"{source}: line {number}, a cell is not a number: {bad.strip()!r}") from None
        bad = _unusable(frame)
        if bad.any():
            raise InputError(f"{source}: line {number}, cell {int(np.argmax(bad))} is not a finite number "
                             f"({frame[bad][0]:g}); {WITHIN}")
        yield frame.reshape(rows, cols)


def _is_number(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


def save_frames_csv(stream: ContactStream, path: str | Path) -> Path:
    """Write frames as the firmware streams them: one comma-separated row-major line per frame."""
    path = Path(path)
    flat = stream.frames.reshape(stream.n_frames, -1)
    integer = np.all(flat == np.round(flat))
    np.savetxt(path, flat, delimiter=",", fmt="%d" if integer else "%.6g")
    return path
