"""Tables of presses: what a scene simulates and what a user's rig recorded look the same.

A SensorTable holds one row per press: channel columns (inputs), target columns (what to
learn, units in their names) and a group id per row (all repeats of one position-depth
pair share a group, so grouped splits can keep them on one side).
"""
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from data.errors import InputError


@dataclass
class SensorTable:
    frame: pd.DataFrame
    channel_columns: list[str]
    target_columns: list[str]
    groups: np.ndarray
    description: dict = field(default_factory=dict)

    @property
    def channels(self) -> np.ndarray:
        return self.frame[self.channel_columns].to_numpy(dtype=np.float64)

    @property
    def targets(self) -> np.ndarray:
        return self.frame[self.target_columns].to_numpy(dtype=np.float64)


def read_table_file(path: str | Path) -> pd.DataFrame:
    """Read a CSV or Parquet file; a missing, unreadable or empty file is a one-line InputError."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file")
    suffix = path.suffix.lower()
    try:
        if suffix == ".csv":
            frame = pd.read_csv(path)
        elif suffix in (".parquet", ".pq"):
            frame = pd.read_parquet(path)
        else:
            raise InputError(f"{path}: unsupported file type '{suffix}', expected .csv or .parquet")
    except pd.errors.EmptyDataError:
        raise InputError(f"{path}: file is empty") from None
    except InputError:
        raise
    except Exception as error:  # parser errors differ by engine; name the file and the cause
        raise InputError(f"{path}: cannot read table ({type(error).__name__}: {error})".splitlines()[0]) from None
    if frame.empty:
        raise InputError(f"{path}: table has no rows")
    return frame


def check_numeric_columns(frame: pd.DataFrame, columns: list[str], what: str, source: str) -> None:
    """Every named column exists, is numeric and finite; otherwise one line naming the column."""
    missing = [c for c in columns if c not in frame.columns]
    if missing:
        raise InputError(f"{source}: missing {what} column(s) {', '.join(missing)}; "
                         f"found {', '.join(map(str, frame.columns))}")
    for column in columns:
        values = pd.to_numeric(frame[column], errors="coerce")
        bad = values.isna() & frame[column].notna()
        if bad.any():
            row = int(np.flatnonzero(bad.to_numpy())[0])
            raise InputError(f"{source}: {what} column '{column}' has a non-numeric value "
                             f"{frame[column].iloc[row]!r} in row {row}")
        finite = np.isfinite(values.to_numpy(dtype=np.float64))
        if not finite.all():
            row = int(np.flatnonzero(~finite)[0])
            raise InputError(f"{source}: {what} column '{column}' has a missing or infinite "
                             f"value in row {row}")


class TableSource:
    """A user's recording: `data=table data.source.path=rig.csv`, columns named in the config."""

    def __init__(self, path: str, channel_columns: list[str], target_columns: list[str],
                 group_columns: list[str] | None = None):
        self.path = path
        self.channel_columns = list(channel_columns)
        self.target_columns = list(target_columns)
        self.group_columns = list(group_columns) if group_columns else None

    def load(self) -> SensorTable:
        frame = read_table_file(self.path)
        check_numeric_columns(frame, self.channel_columns, "channel", self.path)
        check_numeric_columns(frame, self.target_columns, "target", self.path)
        columns = self.channel_columns + self.target_columns
        numeric = frame[columns].apply(pd.to_numeric).astype(np.float64)
        if self.group_columns:
            missing = [c for c in self.group_columns if c not in frame.columns]
            if missing:
                raise InputError(f"{self.path}: missing group column(s) {', '.join(missing)}")
            groups = frame.groupby(self.group_columns, sort=True, dropna=False).ngroup().to_numpy()
        else:
            groups = np.arange(len(frame))
        return SensorTable(numeric, self.channel_columns, self.target_columns, groups,
                           {"source": "table", "path": str(self.path)})
