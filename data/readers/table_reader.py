"""Reading users' CSV and Parquet files, and checking their columns: every problem is one line
naming the file, the column and the row.

A numeric column must hold numbers a model can compute with: booleans, dates, time spans and
complex numbers are refused rather than cast (True would become 1.0, a date nanoseconds since
1970, and a complex number would lose its imaginary part, all silently); every value must be
finite as MODEL_DTYPE, the type the models compute in, so 1e308 (finite in float64, infinite in
float32) is refused with the limit; and a column whose name carries a unit must lie in that
unit's physical range (data/units.py: a resistance is never negative).
"""
from pathlib import Path

import numpy as np
import pandas as pd

from common.errors import InputError
from common.progress import progress
from data.units import first_outside, physical_range

# The torch nets and the exported ONNX graph compute in float32, and scikit-learn's trees cast
# their inputs to float32 too: a value must survive that cast.
MODEL_DTYPE = np.float32
MODEL_DTYPE_MAX = float(np.finfo(MODEL_DTYPE).max)
# What a column of each refused dtype kind holds (numpy's dtype.kind letters).
REFUSED_KINDS = {"b": "booleans (True/False)", "M": "dates or times", "m": "time spans",
                 "c": "complex numbers"}
CSV_CHUNK_ROWS = 200_000   # a progress update per chunk: well under a second each


def read_table_file(path: str | Path) -> pd.DataFrame:
    """Read a CSV or Parquet file; a missing, unreadable or empty file is a one-line InputError.
    A large file shows progress (a bar on a terminal, log lines elsewhere) from its first chunk."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file")
    suffix = path.suffix.lower()
    if suffix not in (".csv", ".parquet", ".pq"):
        raise InputError(f"{path}: unsupported file type '{suffix}', expected .csv or .parquet")
    bar = progress(desc=f"reading {path.name} ({path.stat().st_size / 1e6:.1f} MB)", unit="rows", announce=True)
    try:
        if suffix == ".csv":
            chunks = []
            with pd.read_csv(path, chunksize=CSV_CHUNK_ROWS) as reader:
                for chunk in reader:
                    chunks.append(chunk)
                    bar.update(len(chunk))
            frame = pd.concat(chunks, ignore_index=True) if chunks else pd.DataFrame()
        else:
            frame = pd.read_parquet(path)
            bar.update(len(frame))
    except pd.errors.EmptyDataError:
        raise InputError(f"{path}: file is empty") from None
    except Exception as error:  # parser errors differ by engine; name the file and the cause
        raise InputError(f"{path}: cannot read table ({type(error).__name__}: {error})".splitlines()[0]) from None
    finally:
        bar.close()
    if frame.empty:
        raise InputError(f"{path}: table has no rows")
    return frame


def where(source, row: int) -> str:
    """A data row as a user finds it: the file line of a CSV (its header is line 1), else the
    1-based row number."""
    return f"line {row + 2}" if str(source).lower().endswith(".csv") else f"row {row + 1}"


def check_numeric_columns(frame: pd.DataFrame, columns: list[str], what: str, source: str) -> None:
    """Every named column exists and holds numbers a model can take (numeric_column, then
    check_model_values); otherwise one line naming the column, the row and the problem."""
    check_columns_exist(frame, columns, what, source)
    for column in columns:
        check_model_values(numeric_column(frame[column], column, what, source), column, what, source)


def check_columns_exist(frame: pd.DataFrame, columns: list[str], what: str, source: str,
                        setting: str | None = None) -> None:
    """Every named column is in the frame; else one line naming them, the columns found and, when
    given, the setting that names them (`data.target_columns`)."""
    missing = [c for c in columns if c not in frame.columns]
    if missing:
        fix = f"; set {setting}=[...]" if setting else ""
        raise InputError(f"{source}: missing {what} column(s) {', '.join(map(str, missing))}; "
                         f"found {', '.join(map(str, frame.columns))}{fix}")


def numeric_column(raw: pd.Series, column: str, what: str, source: str, hint: str = "") -> np.ndarray:
    """A column's cells as float64 (NaN where empty): text, booleans, dates, time spans and
    complex numbers are one-line errors naming the cell (and ending in `hint`)."""
    kind = getattr(raw.dtype, "kind", "O")
    values = pd.to_numeric(raw, errors="coerce")
    kind = kind if kind in REFUSED_KINDS else values.dtype.kind  # an object column of bools or complex numbers
    if kind in REFUSED_KINDS:
        raise InputError(f"{source}: {what} column '{column}' holds {REFUSED_KINDS[kind]}, not numbers in its "
                         f"unit; refused rather than cast to float (write the numbers themselves){hint}")
    bad = values.isna() & raw.notna()
    if bad.any():
        row = int(np.flatnonzero(bad.to_numpy())[0])
        raise InputError(f"{source}: {what} column '{column}' has a non-numeric value "
                         f"{raw.iloc[row]!r} in {where(source, row)}{hint}")
    return values.to_numpy(dtype=np.float64, na_value=np.nan)


def model_value_bounds(columns: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Per column, the lowest and highest value a model can take: MODEL_DTYPE's range, narrowed to
    the unit's physical range where the name carries a unit (a resistance is never negative)."""
    rules = [physical_range(column) for column in columns]
    low = np.array([-MODEL_DTYPE_MAX if r is None else max(r.low, -MODEL_DTYPE_MAX) for r in rules])
    high = np.array([MODEL_DTYPE_MAX if r is None else min(r.high, MODEL_DTYPE_MAX) for r in rules])
    return low, high


def check_model_block(frame: pd.DataFrame, columns: list[str], what: str, source: str) -> None:
    """check_model_values on every column, in one pass over the block when all of them hold (a
    scene's table has thousands of channel columns): each column's minimum and maximum decide it
    (NaN propagates into both); only a table that fails is checked column by column, for the
    same first error."""
    try:
        values = frame[columns].to_numpy(dtype=np.float64)
    except (TypeError, ValueError):                    # not numbers: the column-by-column error
        values = np.empty((0, 0))
    if values.shape[1:] == (len(columns),) and len(values):
        low, high = model_value_bounds(columns)
        if (values.min(axis=0) >= low).all() and (values.max(axis=0) <= high).all():
            return
    for column in columns:
        check_model_values(frame[column].to_numpy(dtype=np.float64), column, what, source)


def check_model_values(values: np.ndarray, column: str, what: str, source: str) -> None:
    """A column's numbers are finite, still finite as MODEL_DTYPE, and in the physical range of the
    unit its name carries (data/units.py); `values` 1-d, row k is `where(source, k)`."""
    finite = np.isfinite(values)
    if not finite.all():
        row = int(np.flatnonzero(~finite)[0])
        raise InputError(f"{source}: {what} column '{column}' has a missing or infinite "
                         f"value in {where(source, row)}")
    too_large = np.abs(values) > MODEL_DTYPE_MAX
    if too_large.any():
        row = int(np.flatnonzero(too_large)[0])
        raise InputError(f"{source}: {what} column '{column}' has {values[row]:g} in {where(source, row)}, beyond "
                         f"the largest float32 ({MODEL_DTYPE_MAX:.4g}): the models compute in float32, where it "
                         "is infinite")
    outside = first_outside(values, column)
    if outside is not None:
        row, value, rule = outside
        raise InputError(f"{source}: {what} column '{column}' has {value:g} in {where(source, row)}; "
                         f"{rule.describe()}")
