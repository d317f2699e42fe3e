"""Users' own time-series recordings: NPZ arrays or a long-format table, as a RecordingSet.

NPZ: `X` of shape (n, channels, length), or an object array of per-recording (channels,
length_i) arrays (cut to the shortest); `y` labels (n,); optional `force_level` (n,) in newtons
and `channel_names` (channels,).
Long table (CSV/Parquet): one row per time step with a recording id column, a time column,
the channel columns and the label column(s); optional force-level column. Recordings are
sorted by time and cut to the shortest.
Any schema problem is a one-line InputError naming the file and what was expected.
"""
from pathlib import Path

import numpy as np
import pandas as pd

from data.errors import InputError
from data.recordings import RecordingSet
from data.table_files import check_numeric_columns, read_table_file


def _stack(arrays, source):
    lengths = [a.shape[-1] for a in arrays]
    channels = {a.shape[0] for a in arrays}
    if len(channels) != 1:
        raise InputError(f"{source}: recordings have different channel counts {sorted(channels)}")
    shortest = min(lengths)
    return np.stack([a[:, :shortest] for a in arrays]).astype(np.float32)


def load_npz(path, label="y", sample_rate_hz=250.0) -> RecordingSet:
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file")
    try:
        archive = np.load(path, allow_pickle=True)
    except Exception as error:
        raise InputError(f"{path}: cannot read NPZ ({type(error).__name__})") from None
    for key in ("X", "y"):
        if key not in archive:
            raise InputError(f"{path}: missing array '{key}'; found {', '.join(archive.files)}")
    X, y = archive["X"], archive["y"]
    if X.dtype == object:
        X = _stack([np.asarray(a, dtype=np.float64) for a in X], path)
    if X.ndim != 3:
        raise InputError(f"{path}: X must be (n, channels, length), got shape {X.shape}")
    if not np.issubdtype(X.dtype, np.number):
        raise InputError(f"{path}: X must be numeric, got dtype {X.dtype}")
    if len(y) != len(X):
        raise InputError(f"{path}: y has {len(y)} labels for {len(X)} recordings")
    if not np.isfinite(X).all():
        raise InputError(f"{path}: X contains NaN or inf")
    names = [str(c) for c in archive["channel_names"]] if "channel_names" in archive \
        else [f"channel_{k}" for k in range(X.shape[1])]
    labels = pd.DataFrame({label: y})
    if "force_level" in archive:
        labels["force_level_n"] = np.asarray(archive["force_level"], dtype=np.float64)
    return RecordingSet(X.astype(np.float32), names, labels, sample_rate_hz, {"source": "npz", "path": str(path)})


def load_long_table(path, recording_column, time_column, channel_columns, label_columns,
                    force_column=None, sample_rate_hz=250.0) -> RecordingSet:
    """One recording per id, channels in the given order, labels from its first row."""
    frame = read_table_file(path)
    check_numeric_columns(frame, [time_column] + list(channel_columns), "channel/time", str(path))
    needed = [recording_column] + list(label_columns) + ([force_column] if force_column else [])
    missing = [c for c in needed if c not in frame.columns]
    if missing:
        raise InputError(f"{path}: missing column(s) {', '.join(missing)}; found {', '.join(map(str, frame.columns))}")
    arrays, rows = [], []
    for recording, part in frame.sort_values([recording_column, time_column]).groupby(recording_column, sort=True):
        arrays.append(part[list(channel_columns)].to_numpy(dtype=np.float64).T)
        first = part.iloc[0]
        row = {c: first[c] for c in label_columns}
        if force_column:
            row["force_level_n"] = float(first[force_column])  # the data module splits on this name
        rows.append(row)
    return RecordingSet(_stack(arrays, path), list(channel_columns), pd.DataFrame(rows), sample_rate_hz,
                        {"source": "table", "path": str(path)})


class NpzRecordings:
    """`data=recordings_npz data.source.path=rig.npz`: a user's NPZ as a recordings source."""

    def __init__(self, path, label="y", sample_rate_hz=250.0):
        self.path, self.label, self.sample_rate_hz = path, label, sample_rate_hz

    def load(self) -> RecordingSet:
        return load_npz(self.path, self.label, self.sample_rate_hz)


class LongTableRecordings:
    """`data=recordings_table data.source.path=rig.parquet`: a user's long table as a recordings source."""

    def __init__(self, path, recording_column, time_column, channel_columns, label_columns,
                 force_column=None, sample_rate_hz=250.0):
        self.path, self.recording_column, self.time_column = path, recording_column, time_column
        self.channel_columns, self.label_columns = list(channel_columns), list(label_columns)
        self.force_column, self.sample_rate_hz = force_column, sample_rate_hz

    def load(self) -> RecordingSet:
        return load_long_table(self.path, self.recording_column, self.time_column, self.channel_columns,
                               self.label_columns, self.force_column, self.sample_rate_hz)
