"""Users' own time-series recordings: NPZ arrays or a long-format table, as a RecordingSet.

NPZ: `X`, a numeric array of shape (n, channels, length) (recordings of different lengths: cut
or pad them to a common length before saving); `y` labels (n,), numbers or strings, none missing
(NaN) or empty; optional `force_level` (n,) in newtons, finite and >= 0, `channel_names`
(channels,), `split` (n,) with train / val / test per recording (data.split=predefined) and
`sample_rate_hz` (a scalar). The file is opened with allow_pickle=False: an object array (which
numpy can only store pickled, and unpickling can run code) is refused.
Long table (CSV/Parquet): one row per time step with a recording id column, a time column in
seconds, the channel columns and the label column(s); optional force-level and split columns.
Recordings are sorted by time; recordings of different lengths are an error unless a rule is
stated (`lengths: crop` cuts all to the shortest, `pad` zero-pads all to the longest). The
sample rate is the config's, else the NPZ's `sample_rate_hz`, else (table) one over the median
time step; with none of them it is unknown (None) and the exported model says so.
Any schema problem is a one-line InputError naming the file and what was expected.
"""
from pathlib import Path

import numpy as np
import pandas as pd

from common.errors import InputError
from common.progress import progress
from data.readers.table_reader import (
    REFUSED_KINDS,
    check_columns_exist,
    check_model_values,
    check_numeric_columns,
    numeric_column,
    read_table_file,
    where,
)
from data.recording_set import RecordingSet
from data.splits.indices import check_one_value_per_group, split_values

# What to save instead of an object array, per array of the NPZ.
NPZ_EXPECTED = {"X": "a numeric float array X of shape (n, channels, length)",
                "y": "y as a numeric or string array of shape (n,)",
                "force_level": "force_level as a numeric float array of shape (n,) in newtons",
                "channel_names": "channel_names as a string array of shape (channels,)",
                "split": "split as a string array of shape (n,) with train / val / test",
                "sample_rate_hz": "sample_rate_hz as a numeric scalar"}
LENGTH_RULES = ("equal", "crop", "pad")


def _stack(arrays, source, lengths="equal"):
    """(n, channels, steps) from recordings of maybe different lengths, by the stated rule."""
    if lengths not in LENGTH_RULES:
        raise InputError(f"data.source.lengths must be one of {', '.join(LENGTH_RULES)}, got {lengths!r}")
    steps = [a.shape[-1] for a in arrays]
    channels = {a.shape[0] for a in arrays}
    if len(channels) != 1:
        raise InputError(f"{source}: recordings have different channel counts {sorted(channels)}")
    if min(steps) != max(steps) and lengths == "equal":
        raise InputError(f"{source}: recordings have different lengths ({min(steps)} to {max(steps)} steps); "
                         "set data.source.lengths=crop (cut all to the shortest) or pad (zeros after the end, "
                         "to the longest)")
    if lengths == "pad":
        longest = max(steps)
        return np.stack([np.pad(a, ((0, 0), (0, longest - a.shape[-1]))) for a in arrays])
    shortest = min(steps)
    return np.stack([a[:, :shortest] for a in arrays])


def _sample_rate(configured, declared, source) -> float | None:
    """The config's rate, else the data's own; both given and different is an error (which is real?)."""
    for name, value in (("data.source.sample_rate_hz", configured), ("the data's sample rate", declared)):
        if value is not None and not (np.isfinite(float(value)) and float(value) > 0):
            raise InputError(f"{source}: {name} must be a positive number of hertz, got {value!r}")
    if configured is not None and declared is not None and not np.isclose(float(configured), float(declared),
                                                                           rtol=1e-3):
        raise InputError(f"{source}: data.source.sample_rate_hz={configured} but the data say {float(declared):g} Hz")
    rate = configured if configured is not None else declared
    return None if rate is None else float(rate)


def _npz_array(archive, key, path) -> np.ndarray:
    """One array of the archive; numpy refuses an object array under allow_pickle=False."""
    try:
        return archive[key]
    except ValueError as error:
        if "pickle" not in str(error):  # a damaged .npy header inside the archive
            raise InputError(f"{path}: array '{key}' cannot be read (ValueError: {str(error)[:100]})"
                             .splitlines()[0]) from None
        raise InputError(f"{path}: array '{key}' is an object (pickled) array, which is refused because "
                         f"loading it could run code; save {NPZ_EXPECTED[key]}") from None
    except Exception as error:  # a damaged archive: zipfile's BadZipFile, zlib, EOFError, OSError
        raise InputError(f"{path}: array '{key}' cannot be read ({type(error).__name__}: {str(error)[:100]})"
                         .splitlines()[0]) from None


def _first_bad(values, bad, name, path, problem: str) -> None:
    """One line for the first flagged entry: `problem` is formatted with its value."""
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise InputError(f"{path}: {name}[{k}] is {problem.format(values[k])}")


def _check_labels(y, n, path) -> None:
    """One label per recording, none missing: a NaN or empty label would become a class of its own."""
    if y.ndim != 1:
        raise InputError(f"{path}: y must be one label per recording, shape ({n},), got shape {y.shape}")
    if len(y) != n:
        raise InputError(f"{path}: y has {len(y)} labels for {n} recordings")
    if y.dtype.kind in REFUSED_KINDS and y.dtype.kind != "b":  # True/False are fine as class names
        raise InputError(f"{path}: y holds {REFUSED_KINDS[y.dtype.kind]}; labels are class names or numbers")
    if np.issubdtype(y.dtype, np.inexact):
        _first_bad(y, np.isnan(y), "y", path, "missing (NaN)")
        _first_bad(y, ~np.isfinite(y), "y", path, "not finite ({})")
    elif np.issubdtype(y.dtype, np.str_) or np.issubdtype(y.dtype, np.bytes_):
        _first_bad(y, np.char.strip(y) == y.dtype.type(), "y", path, "an empty string ({!r})")


def _check_force_levels(force, n, path) -> np.ndarray:
    """Force levels in newtons: the force_level split and virtual levels compute with them."""
    if not (np.issubdtype(force.dtype, np.integer) or np.issubdtype(force.dtype, np.floating)):
        raise InputError(f"{path}: force_level must be numeric (newtons), got dtype {force.dtype}")
    if force.ndim != 1 or len(force) != n:
        raise InputError(f"{path}: force_level has {force.size} values for {n} recordings; expected shape ({n},)")
    force = force.astype(np.float64)
    _first_bad(force, np.isnan(force), "force_level", path, "missing (NaN)")
    _first_bad(force, ~np.isfinite(force), "force_level", path, "not finite ({})")
    _first_bad(force, force < 0, "force_level", path, "negative ({} N)")
    return force


def _npz_split(split, n, path) -> np.ndarray:
    if split.ndim != 1 or len(split) != n:
        raise InputError(f"{path}: split has {split.size} values for {n} recordings; expected shape ({n},)")
    return split_values(split, f"{path}: array 'split'", lambda k: f"split[{k}]")


def _npz_sample_rate(rate, path) -> float:
    if rate.size != 1 or not np.issubdtype(rate.dtype, np.number):
        raise InputError(f"{path}: sample_rate_hz must be one number (hertz), got shape {rate.shape} dtype {rate.dtype}")
    return float(rate.reshape(()))


def read_npz(path, required=("X", "y")) -> dict[str, np.ndarray]:
    """The arrays of NPZ_EXPECTED the archive holds, read with allow_pickle=False; `required`
    ones missing, a pickle or a damaged archive is a one-line InputError."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file")
    try:
        archive = np.load(path, allow_pickle=False)
    except ValueError as error:  # an object .npy or a pickle: numpy refuses it without unpickling
        if "pickle" not in str(error):
            raise InputError(f"{path}: cannot read NPZ (ValueError)") from None
        raise InputError(f"{path}: pickled data is refused (loading it could run code); save an NPZ "
                         f"with {NPZ_EXPECTED['X']} and labels y") from None
    except Exception as error:
        raise InputError(f"{path}: cannot read NPZ ({type(error).__name__})") from None
    if not isinstance(archive, np.lib.npyio.NpzFile):
        raise InputError(f"{path}: a single array, not an NPZ archive; save one with np.savez(path, X=..., y=...)")
    with archive:
        for key in required:
            if key not in archive:
                raise InputError(f"{path}: missing array '{key}'; found {', '.join(archive.files)}")
        return {key: _npz_array(archive, key, path) for key in NPZ_EXPECTED if key in archive}


def npz_recordings(arrays, path) -> tuple[np.ndarray, list[str], float | None]:
    """X (n, channels, length) of real, finite numbers; its channel names (channel_<k> when the
    file names none); the sample rate the file declares (None without one)."""
    X = arrays["X"]
    if X.ndim != 3:
        raise InputError(f"{path}: X must be (n, channels, length), got shape {X.shape}")
    if X.dtype.kind not in "iuf":  # complex would lose its imaginary part, booleans become 0/1: refused, not cast
        raise InputError(f"{path}: X must be real numbers (integers or floats), got dtype {X.dtype}")
    if X.dtype.kind == "f" and not np.isfinite(X).all():
        k, c, t = np.unravel_index(int(np.flatnonzero(~np.isfinite(X))[0]), X.shape)
        raise InputError(f"{path}: X contains NaN or inf, first at X[{k}, {c}, {t}] ({X[k, c, t]})")
    names = arrays.get("channel_names")
    names = [str(c) for c in names] if names is not None else [f"channel_{k}" for k in range(X.shape[1])]
    if len(names) != X.shape[1]:
        raise InputError(f"{path}: channel_names has {len(names)} names for {X.shape[1]} channels")
    declared = _npz_sample_rate(arrays["sample_rate_hz"], path) if "sample_rate_hz" in arrays else None
    return X, names, declared


def load_npz(path, label="y", sample_rate_hz=None) -> RecordingSet:
    path = Path(path)
    arrays = read_npz(path)
    X, names, declared = npz_recordings(arrays, path)
    y = arrays["y"]
    _check_labels(y, len(X), path)
    labels = pd.DataFrame({label: y})
    if "force_level" in arrays:
        labels["force_level_n"] = _check_force_levels(arrays["force_level"], len(X), path)
    if "split" in arrays:
        labels["split"] = _npz_split(arrays["split"], len(X), path)
    return RecordingSet(X, names, labels, _sample_rate(sample_rate_hz, declared, path),
                        {"source": "npz", "path": str(path)})


def median_step_rate(recordings, time_column, path, remedy="set data.source.sample_rate_hz") -> float:
    """One over the median time step within recordings (seconds, as the time column's `_s` says);
    `recordings`: table_recordings' groups (or one recording's rows)."""
    steps = recordings[time_column].diff().dropna().to_numpy(dtype=np.float64)
    step_s = float(np.median(steps)) if steps.size else float("nan")
    if not step_s > 0:
        raise InputError(f"{path}: time column '{time_column}' gives no positive time step (repeated time stamps?); "
                         + remedy)
    return 1.0 / step_s


def table_recordings(frame, recording_column, time_column, path):
    """A long table's recordings in id order, each one's rows in time order (stable: equal times,
    or no time column, keep the file's order), as pandas groups."""
    _check_recording_ids(frame, recording_column, path)
    order = [recording_column] + ([time_column] if time_column else [])
    return frame.sort_values(order, kind="stable").groupby(recording_column, sort=True)


def _check_recording_ids(frame, recording_column, path) -> None:
    ids = frame[recording_column]
    if ids.isna().any():
        row = int(np.flatnonzero(ids.isna().to_numpy())[0])
        raise InputError(f"{path}: recording column '{recording_column}' is empty in {where(path, row)}")


def _check_recording_columns(frame, recording_column, label_columns, force_column, path) -> None:
    """Every row names its recording and carries its labels (and force level), one value per
    recording: the labels of a recording are read from one row, so a missing or changing one
    would silently mislabel it."""
    _check_recording_ids(frame, recording_column, path)
    ids = frame[recording_column]
    for column in label_columns:
        values = frame[column]
        if values.dtype.kind in "cMm":
            raise InputError(f"{path}: label column '{column}' holds {REFUSED_KINDS[values.dtype.kind]}; "
                             "labels are class names or numbers")
        empty = values.isna() | (values.astype(str).str.strip() == "")
        if empty.any():
            row = int(np.flatnonzero(empty.to_numpy())[0])
            raise InputError(f"{path}: label column '{column}' is empty in {where(path, row)}; every row needs "
                             "its recording's label")
        check_one_value_per_group(values.astype(str).to_numpy(), ids.to_numpy(), f"{path}: column '{column}'",
                                  "recording", "label")
    if force_column:
        check_columns_exist(frame, [force_column], "force level", path)
        levels = numeric_column(frame[force_column], force_column, "force level", path)
        check_model_values(levels, force_column, "force level", path)
        if (levels < 0).any():  # stored as force_level_n: newtons, whatever the column's own name
            row = int(np.flatnonzero(levels < 0)[0])
            raise InputError(f"{path}: force level column '{force_column}' has {levels[row]:g} in {where(path, row)}; "
                             "a force level in newtons is >= 0")
        check_one_value_per_group(levels, ids.to_numpy(), f"{path}: column '{force_column}'", "recording",
                                  "force level")


def load_long_table(path, recording_column, time_column, channel_columns, label_columns,
                    force_column=None, sample_rate_hz=None, split_column="split", lengths="equal") -> RecordingSet:
    """One recording per id, channels in the given order, labels from its rows (one value each)."""
    if not list(channel_columns):
        raise InputError("data.source.channel_columns is empty: name at least one channel column")
    frame = read_table_file(path)
    check_numeric_columns(frame, [time_column] + list(channel_columns), "channel/time", str(path))
    needed = [recording_column] + list(label_columns)
    missing = [c for c in needed if c not in frame.columns]
    if missing:
        raise InputError(f"{path}: missing column(s) {', '.join(missing)}; found {', '.join(map(str, frame.columns))}")
    _check_recording_columns(frame, recording_column, label_columns, force_column, path)
    has_split = bool(split_column) and split_column in frame.columns
    if has_split:  # every row's value checked, and one value per recording: a recording is one sample
        values = split_values(frame[split_column].to_numpy(), f"{path}: column '{split_column}'",
                              lambda row: where(path, row))
        check_one_value_per_group(values, frame[recording_column].to_numpy(), f"{path}", "recording")
        frame = frame.assign(**{split_column: values})
    arrays, rows = [], []
    parts = table_recordings(frame, recording_column, time_column, path)
    for recording, part in progress(parts, desc=f"recordings of {Path(path).name}", unit="recordings"):
        arrays.append(part[list(channel_columns)].to_numpy(dtype=np.float64).T)
        first = part.iloc[0]
        row = {c: first[c] for c in label_columns}
        if force_column:
            row["force_level_n"] = float(first[force_column])  # the data module splits on this name
        if has_split:
            row["split"] = first[split_column]
        rows.append(row)
    rate = _sample_rate(sample_rate_hz, median_step_rate(parts, time_column, path), path)
    return RecordingSet(_stack(arrays, path, lengths), list(channel_columns), pd.DataFrame(rows), rate,
                        {"source": "table", "path": str(path)})


class NpzRecordings:
    """`data=recordings_npz data.path=rig.npz`: a user's NPZ as a recordings source."""

    def __init__(self, path, label="y", sample_rate_hz=None):
        self.path, self.label, self.sample_rate_hz = path, label, sample_rate_hz

    def load(self) -> RecordingSet:
        return load_npz(self.path, self.label, self.sample_rate_hz)


class LongTableRecordings:
    """`data=recordings_table data.path=rig.parquet`: a user's long table as a recordings source."""

    def __init__(self, path, recording_column, time_column, channel_columns, label_columns,
                 force_column=None, sample_rate_hz=None, split_column="split", lengths="equal"):
        self.path, self.recording_column, self.time_column = path, recording_column, time_column
        self.channel_columns, self.label_columns = list(channel_columns), list(label_columns)
        self.force_column, self.sample_rate_hz = force_column, sample_rate_hz
        self.split_column, self.lengths = split_column, lengths

    def load(self) -> RecordingSet:
        return load_long_table(self.path, self.recording_column, self.time_column, self.channel_columns,
                               self.label_columns, self.force_column, self.sample_rate_hz, self.split_column,
                               self.lengths)
