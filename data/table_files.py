"""Reading users' CSV and Parquet files, and checking their columns: every problem is one line
naming the file, the column and the row."""
from pathlib import Path

import numpy as np
import pandas as pd

from data.errors import InputError


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


def where(source, row: int) -> str:
    """A data row as a user finds it: the file line of a CSV (its header is line 1), else the
    1-based row number."""
    return f"line {row + 2}" if str(source).lower().endswith(".csv") else f"row {row + 1}"


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
                             f"{frame[column].iloc[row]!r} in {where(source, row)}")
        finite = np.isfinite(values.to_numpy(dtype=np.float64))
        if not finite.all():
            row = int(np.flatnonzero(~finite)[0])
            raise InputError(f"{source}: {what} column '{column}' has a missing or infinite "
                             f"value in {where(source, row)}")
