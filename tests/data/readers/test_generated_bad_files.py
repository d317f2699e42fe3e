"""Generated bad files through every reader train.py and predict.py use, called as they call them:
CSV and Parquet tables through the regression datamodule's setup (`data=table`), NPZ recordings
and long tables of recordings through the time-series datamodule's setup (`data=recordings_npz`,
`data=recordings_table`), frame streams through data/readers/contact_streams.py (the capacitive tracking
study's reader), ONNX models with malformed metadata and bad input tables through predict.py's
main(argv); and a few end to end through the commands as subprocesses.

Each file starts as a small valid file, and Hypothesis draws faults for it: truncated bytes,
bytes that are not UTF-8, NUL bytes, empty and header-only files, one row, missing, renamed and
duplicated columns, ragged rows, recordings of mismatched lengths, wrong dtypes, object (pickled)
arrays, and the values 1e308, -1e308, ±3.5e38 (beyond float32), NaN, ±inf and integers beyond
int64. Two outcomes are allowed: a result whose arrays (or predict.py's output file) hold only
finite numbers, or an InputError whose message is one line (predict.py: exit 2, one line on
stderr, no output file). Anything else fails with the drawn file. A draw without faults must
load, and give back the values written.

Files written per CI run (profile "ci"): FILES below, 2,150 in all; each test asserts it wrote
at least its share and prints its count (`pytest -s` shows them). The "thorough" profile writes
20x more.
"""
import contextlib
import io
import json
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
from hydra.errors import InstantiationException
from hydra.utils import instantiate
from hypothesis import given
from hypothesis import strategies as st
from tests.predict_support import (
    CHANNELS,
    WINDOW_STEPS,
    classification_metadata,
    classification_model,
    predict_main,
    regression_metadata,
    regression_model,
    save,
)
from tests.models.test_numerical_properties import examples

from common.errors import InputError
from data.readers.contact_streams import frames_from_lines, load_frames

ROOT = Path(__file__).resolve().parents[3]
FILES = {"csv_table": 350, "parquet_table": 250, "npz": 350, "long_table": 300, "frames_csv": 200,
         "frames_npy": 150, "onnx_metadata": 200, "predict_input": 350}
assert sum(FILES.values()) == 2150

# Cell texts of users' files: the extremes, spellings of missing and infinite values, integers
# beyond int64 and uint64, and text where a number belongs.
EXTREME_CELLS = ["1e308", "-1e308", "3.5e38", "-3.5e38", "1e309", "-1e309", "5e-324", "nan", "NaN", "inf", "-inf",
                 "Infinity", "99999999999999999999999", "-18446744073709551617", "9223372036854775808"]
JUNK_CELLS = ["", " ", "NA", "null", "None", "abc", "1,5", "0x1F", "1e", "True", "\u0661\u0662", '"2.5"', "'3'", "--1"]
EXTREME_FLOATS = [1e308, -1e308, 3.5e38, -3.5e38, 5e-324, np.nan, np.inf, -np.inf, 0.0]
# Faults of a text table: of its columns, rows, cells and bytes. CLEAN_FAULTS keep a file valid.
TEXT_FAULTS = ["extreme", "junk", "drop_column", "duplicate_column", "rename_column", "ragged", "header_only",
               "one_row", "empty", "truncate", "non_utf8", "nul", "extra_column", "bom_crlf"]
CLEAN_FAULTS = {"extra_column", "bom_crlf"}


class Blob(bytes):
    """A generated file's bytes, shown short when Hypothesis prints a failing example (the whole
    file is left in the test's tmp_path, under the reader's file name)."""

    def __repr__(self) -> str:
        return f"<{len(self)} bytes: {bytes(self[:160])!r}{'...' if len(self) > 160 else ''}>"

    def _repr_pretty_(self, printer, cycle) -> None:
        printer.text(repr(self))


class Files:
    """Writes every generated file into one folder, counts them and what became of them."""

    def __init__(self, folder: Path):
        self.folder, self.count, self.loaded, self.refused, self.message = folder, 0, 0, 0, ""

    def write(self, name: str, data: bytes) -> Path:
        path = self.folder / name
        path.write_bytes(data)
        self.count += 1
        return path

    def read(self, read):
        """read()'s result, or None for an InputError with a one-line message; any other
        exception propagates and fails the test."""
        try:
            result = read()
        except InputError as error:
            message = str(error)
            assert message.strip() and "\n" not in message and "\r" not in message, repr(message)
            self.refused, self.message = self.refused + 1, message
            return None
        self.loaded += 1
        return result

    def report(self, reader: str) -> None:
        print(f"\n{reader}: {self.count} generated files ({self.loaded} read, {self.refused} refused in one line)")
        assert self.count >= FILES[reader]


def all_finite(*arrays, dtype=np.float64) -> bool:
    with np.errstate(over="ignore"):
        return all(np.isfinite(np.asarray(a, dtype=np.float64).astype(dtype)).all() for a in arrays)


def train_datamodule(cfg, **changes):
    """What train.py does with a composed config (runs/run.py): instantiate(cfg.data).setup(),
    here with `changes` merged into cfg.data; a constructor's InputError is its one line, as train.py
    makes it."""
    try:
        datamodule = instantiate(cfg.data, **changes)
    except InstantiationException as error:
        if isinstance(error.__cause__, InputError):
            raise error.__cause__ from None
        raise
    return datamodule.setup()


# -- text tables --------------------------------------------------------------------------
@st.composite
def faults(draw, kinds=TEXT_FAULTS):
    return draw(st.sets(st.sampled_from(kinds), max_size=3))


@st.composite
def text_file(draw, header: list[str], rows: list[list[str]], chosen: set, protected=()) -> bytes:
    """The CSV bytes of header + rows with the chosen faults applied. `protected` columns keep
    their values under the cell faults (the ones a valid file needs to say anything at all)."""
    header, rows = list(header), [list(r) for r in rows]
    if "header_only" in chosen:
        rows = []
    if "one_row" in chosen:
        rows = rows[:1]
    free = [k for k, name in enumerate(header) if name not in protected] or list(range(len(header)))
    for fault, pool in (("extreme", EXTREME_CELLS), ("junk", JUNK_CELLS)):
        if fault in chosen and rows:
            for _ in range(draw(st.integers(1, 3))):
                row, col = draw(st.integers(0, len(rows) - 1)), draw(st.sampled_from(free))
                rows[row][col] = draw(st.sampled_from(pool))
    if "drop_column" in chosen:
        k = draw(st.integers(0, len(header) - 1))
        header, rows = header[:k] + header[k + 1:], [r[:k] + r[k + 1:] for r in rows]
    if "duplicate_column" in chosen:
        k = draw(st.integers(0, len(header) - 1))
        header, rows = header + [header[k]], [r + [draw(st.sampled_from([r[k], "7", "abc"]))] for r in rows]
    if "rename_column" in chosen:
        k = draw(st.integers(0, len(header) - 1))
        header[k] = draw(st.sampled_from([header[k].upper(), f" {header[k]}", f"{header[k]}_", ""]))
    if "extra_column" in chosen:
        header, rows = header + ["note"], [r + [draw(st.sampled_from(["ok", "", "x,y", "1e308"]))] for r in rows]
    if "ragged" in chosen and rows:
        row = draw(st.integers(0, len(rows) - 1))
        rows[row] = rows[row][:-1] if draw(st.booleans()) else rows[row] + ["1"]
    newline = "\r\n" if "bom_crlf" in chosen else "\n"
    quote = lambda cell: f'"{cell}"' if "," in cell and not cell.startswith('"') else cell  # noqa: E731
    text = newline.join(",".join(quote(c) for c in line) for line in [header] + rows) + newline
    data = ("\ufeff" if "bom_crlf" in chosen else "").encode() + text.encode()
    return Blob(damaged_bytes(draw, data, chosen))


def damaged_bytes(draw, data: bytes, chosen: set) -> bytes:
    if "empty" in chosen:
        return draw(st.sampled_from([b"", b"\n", b"   \n\n"]))
    if "truncate" in chosen and data:
        data = data[:draw(st.integers(0, len(data) - 1))]
    if "non_utf8" in chosen:
        at = draw(st.integers(0, len(data)))
        data = data[:at] + draw(st.sampled_from([b"\xff\xfe", b"\xe9", b"\x80abc", b"\xc3("])) + data[at:]
    if "nul" in chosen:
        at = draw(st.integers(0, len(data)))
        data = data[:at] + b"\x00" + data[at:]
    return data


def number(value: float) -> str:
    return repr(float(value))


# -- CSV and Parquet tables through the regression datamodule (data=table) ------------------
TABLE_CHANNELS = ["r_1_ohm", "r_2_ohm", "r_3_ohm"]
TABLE_TARGETS = ["x_mm", "pressure_pa"]
# data.split: the default (auto, first) and the others a user may set; a clean file must load
# with the default.
TABLE_SPLITS = ["auto", "grouped", "random", "predefined"]


def table_values(seed: int, n_rows: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {**{c: rng.uniform(1e2, 1e5, n_rows) for c in TABLE_CHANNELS}, "x_mm": rng.uniform(0, 50, n_rows),
            "pressure_pa": rng.uniform(0, 1e5, n_rows),
            "split": np.r_[["train", "val", "test"],
                           rng.choice(["train", "val", "test"], n_rows - 3, p=[0.6, 0.2, 0.2])]}


def table_config(compose_config, path: Path):
    return compose_config(["data=table", f"data.path={path}", f"data.channel_columns=[{','.join(TABLE_CHANNELS)}]",
                           f"data.target_columns=[{','.join(TABLE_TARGETS)}]", "data.group_columns=[x_mm]"])


def check_table_result(files: Files, datamodule, values, clean: bool) -> None:
    if datamodule is None:
        assert not clean, f"a clean table was refused: {files.message}"
        return
    assert all_finite(datamodule.X, datamodule.y, datamodule.table.channels)
    if clean:
        np.testing.assert_array_equal(datamodule.y, np.column_stack([values[t] for t in TABLE_TARGETS]))
        np.testing.assert_array_equal(datamodule.table.channels, np.column_stack([values[c] for c in TABLE_CHANNELS]))


def test_csv_tables_through_the_regression_datamodule(tmp_path, compose_config):
    files = Files(tmp_path)
    cfg = table_config(compose_config, tmp_path / "rig.csv")

    @examples(FILES["csv_table"])
    @given(st.data(), st.integers(0, 2 ** 16), st.sampled_from(TABLE_SPLITS))
    def check(data, seed, split):
        chosen = data.draw(faults())
        values = table_values(seed, 20)
        header = TABLE_CHANNELS + TABLE_TARGETS + ["split"]
        rows = [[number(values[c][k]) for c in TABLE_CHANNELS + TABLE_TARGETS] + [values["split"][k]]
                for k in range(20)]
        files.write("rig.csv", data.draw(text_file(header, rows, chosen)))
        datamodule = files.read(lambda: train_datamodule(cfg, split=split))
        check_table_result(files, datamodule, values, chosen <= CLEAN_FAULTS and split == "auto")

    check()
    files.report("csv_table")


# Parquet columns: the type a column is stored as, and what its values become there.
PARQUET_TYPES = ["float64", "float32", "float16", "int64", "uint64", "bool", "numeric_text", "junk_text", "null",
                 "huge_decimal", "timestamp", "list", "dictionary", "binary"]


def parquet_column(kind: str, values: np.ndarray, extremes: list) -> pa.Array:
    values = np.array(values, dtype=np.float64)
    for k, value in enumerate(extremes[:len(values)]):
        values[k] = value
    if kind in ("float64", "float32", "float16"):
        with np.errstate(over="ignore"):
            return pa.array(values.astype(kind))
    if kind == "int64":
        return pa.array(np.nan_to_num(values, posinf=2 ** 62, neginf=-2 ** 62).clip(-2 ** 62, 2 ** 62).astype(np.int64))
    if kind == "uint64":
        return pa.array(np.full(len(values), 2 ** 64 - 1, dtype=np.uint64))
    if kind == "bool":
        return pa.array(values > 0)
    if kind == "numeric_text":
        return pa.array([repr(v) for v in values])
    if kind == "junk_text":
        return pa.array([JUNK_CELLS[k % len(JUNK_CELLS)] for k in range(len(values))])
    if kind == "null":
        return pa.nulls(len(values))
    if kind == "huge_decimal":
        import decimal
        return pa.array([decimal.Decimal(10) ** 30 + k for k in range(len(values))], type=pa.decimal128(38, 0))
    if kind == "timestamp":
        return pa.array(np.arange(len(values)).astype("datetime64[s]"))
    if kind == "list":
        return pa.array([[v, v] for v in values])
    if kind == "dictionary":
        return pa.array([repr(v) for v in values]).dictionary_encode()
    return pa.array([b"\xff\xfe" + bytes([k % 256]) for k in range(len(values))], type=pa.binary())


@st.composite
def parquet_file(draw, columns: dict[str, np.ndarray], text_columns=("split",)) -> tuple[bytes, bool]:
    """Parquet bytes of `columns` with drawn types and faults, and whether the file is clean."""
    chosen = draw(st.sets(st.sampled_from(["types", "extreme", "drop_column", "duplicate_column", "zero_rows",
                                           "one_row", "truncate", "not_parquet"]), max_size=3))
    names, arrays = [], []
    for name, values in columns.items():
        if name in text_columns:
            arrays.append(pa.array(values.tolist()))
        else:
            kind = draw(st.sampled_from(PARQUET_TYPES)) if "types" in chosen else "float64"
            extremes = draw(st.lists(st.sampled_from(EXTREME_FLOATS), max_size=2)) if "extreme" in chosen else []
            arrays.append(parquet_column(kind, values, extremes))
        names.append(name)
    if "drop_column" in chosen:
        k = draw(st.integers(0, len(names) - 1))
        del names[k], arrays[k]
    if "duplicate_column" in chosen:
        k = draw(st.integers(0, len(names) - 1))
        names, arrays = names + [names[k]], arrays + [arrays[k]]
    table = pa.table(arrays, names=names)
    if "zero_rows" in chosen:
        table = table.slice(0, 0)
    if "one_row" in chosen:
        table = table.slice(0, 1)
    buffer = io.BytesIO()
    pq.write_table(table, buffer)
    data = buffer.getvalue()
    if "truncate" in chosen:
        data = data[:draw(st.integers(0, len(data) - 1))]
    if "not_parquet" in chosen:
        data = draw(st.sampled_from([b"", b"a,b\n1,2\n", b"PAR1", b"PAR1\x00\x00PAR1"]))
    return Blob(data), not chosen


def test_parquet_tables_through_the_regression_datamodule(tmp_path, compose_config):
    files = Files(tmp_path)
    cfg = table_config(compose_config, tmp_path / "rig.parquet")

    @examples(FILES["parquet_table"])
    @given(st.data(), st.integers(0, 2 ** 16), st.sampled_from(TABLE_SPLITS))
    def check(data, seed, split):
        values = table_values(seed, 20)
        content, clean = data.draw(parquet_file(values))
        files.write("rig.parquet", content)
        datamodule = files.read(lambda: train_datamodule(cfg, split=split))
        check_table_result(files, datamodule, values, clean and split == "auto")

    check()
    files.report("parquet_table")


# -- recordings through the time-series datamodule (data=recordings_npz, recordings_table) ---
# With base/timeseries.yaml's neutral settings (recordings as they are, each one whole). data.split:
# the default (auto, first) and the others; force_level with the levels the files record. A clean
# file must load with the default.
RECORDING_SPLITS = ["auto", "stratified", "predefined", "force_level"]
LEVELS = {"train_levels": [1.0, 10.0], "val_levels": [5.0, 20.0]}


def check_recordings_result(files: Files, datamodule, signals, clean: bool) -> None:
    if datamodule is None:
        assert not clean, f"clean recordings were refused: {files.message}"
        return
    assert all_finite(datamodule.X_train, datamodule.X_val, datamodule.X_test, datamodule.recordings.signals)
    if "force_level_n" in datamodule.recordings.labels:
        assert all_finite(datamodule.recordings.labels["force_level_n"])
    if clean:
        np.testing.assert_allclose(datamodule.recordings.signals, signals.astype(np.float32))


NPZ_FAULTS = ["x_dtype", "x_shape", "x_extreme", "y_kind", "y_length", "optional", "object", "pickled_y",
              "truncate", "flip_byte", "not_npz", "missing_key", "npy", "zip_junk", "empty_x"]


WRONG_X_SHAPES = [lambda X: X[0] if len(X) else X[:, 0], lambda X: X.reshape(len(X), X[0].size if len(X) else 0),
                  lambda X: X[..., None], lambda X: X[:, :0], lambda X: X[..., :0], lambda X: X.reshape(-1),
                  lambda X: np.float64(1.0)]


@st.composite
def x_array(draw, X: np.ndarray, chosen: set) -> np.ndarray:
    if "x_extreme" in chosen:
        X = X.copy()
        for _ in range(draw(st.integers(1, 3))):
            index = tuple(draw(st.integers(0, s - 1)) for s in X.shape)
            X[index] = draw(st.sampled_from(EXTREME_FLOATS))
    if "empty_x" in chosen:
        X = X[:draw(st.sampled_from([0, 1]))]  # no recording, or one (too few to split)
    if "x_shape" in chosen:
        X = draw(st.sampled_from(WRONG_X_SHAPES))(X)
    if "x_dtype" in chosen:
        kind = draw(st.sampled_from(["float32", "float16", "int64", "uint8", "bool", "complex128", "U3", "S3",
                                     "structured"]))
        with np.errstate(over="ignore", invalid="ignore"):
            if kind == "structured":
                X = np.zeros(np.shape(X), dtype=[("a", "f8"), ("b", "i4")])
            elif kind in ("int64", "uint8"):
                X = np.nan_to_num(np.asarray(X, dtype=np.float64)).clip(0, 200).astype(kind)
            else:
                X = np.asarray(X).astype(kind)
    if "object" in chosen:
        objects = np.empty(len(np.atleast_1d(X)), dtype=object)
        for k in range(len(objects)):
            objects[k] = np.atleast_1d(X)[k]
        X = objects
    return X


@st.composite
def npz_file(draw, n=12, channels=2, steps=5) -> tuple[bytes, int, str, bool]:
    """NPZ bytes, the seed of the clean X, the split setting to use and whether the file is clean."""
    chosen = draw(st.sets(st.sampled_from(NPZ_FAULTS), max_size=3))
    seed = draw(st.integers(0, 2 ** 16))
    X = npz_signals(seed, n, channels, steps)
    arrays = {"X": draw(x_array(X, chosen)), "y": np.array(["soft", "hard"] * (n // 2))}
    split = draw(st.sampled_from(RECORDING_SPLITS))
    arrays["split"] = np.array(["train"] * (n - 4) + ["val", "val", "test", "test"])
    arrays["force_level"] = np.array([1.0, 10.0, 5.0, 20.0] * (n // 4))
    arrays["channel_names"] = np.array([f"ch{k}_v" for k in range(channels)])
    arrays["sample_rate_hz"] = np.array(250.0)
    if "y_kind" in chosen:
        arrays["y"] = draw(st.sampled_from([np.arange(n, dtype=float) % 2, np.r_[np.nan, np.ones(n - 1)],
                                            np.array([""] + ["a"] * (n - 1)), np.array([b"a", b"b"] * (n // 2)),
                                            np.ones((n, 2)), np.array([True, False] * (n // 2)),
                                            np.r_[np.inf, np.zeros(n - 1)], np.arange(n) % 3]))
    if "y_length" in chosen:
        arrays["y"] = arrays["y"][:draw(st.integers(0, n - 1))]
    if "optional" in chosen:
        key = draw(st.sampled_from(["split", "force_level", "channel_names", "sample_rate_hz"]))
        arrays[key] = draw(st.sampled_from([np.array([]), np.array(["x"] * n), np.array([-1.0] * n),
                                            np.array([np.nan] * n), np.array([1e308] * n), np.array([0.0]),
                                            np.array([["a", "b"]]), np.array([1, 2, 3]), np.array(-5.0),
                                            np.array(["train", "TEST ", " Val"] * (n // 3))]))
    if "missing_key" in chosen:
        del arrays[draw(st.sampled_from(["X", "y", "split", "force_level", "channel_names"]))]
    if "pickled_y" in chosen:
        arrays["y"] = np.array([{"label": "a"}] * n, dtype=object)
    buffer = io.BytesIO()
    if "npy" in chosen:
        np.save(buffer, arrays.get("X", X), allow_pickle=True)
    else:
        np.savez(buffer, **arrays)
    data = buffer.getvalue()
    if "zip_junk" in chosen:
        buffer = io.BytesIO()
        with zipfile.ZipFile(buffer, "w") as archive:
            archive.writestr("X.npy", draw(st.sampled_from([b"", b"\x93NUMPY", b"not an array", data[:40]])))
            archive.writestr("y.npy", b"\x93NUMPY\x01\x00")
        data = buffer.getvalue()
    if "truncate" in chosen:
        data = data[:draw(st.integers(0, len(data) - 1))]
    if "flip_byte" in chosen and data:
        at = draw(st.integers(0, len(data) - 1))
        data = data[:at] + bytes([data[at] ^ 0xFF]) + data[at + 1:]
    if "not_npz" in chosen:
        data = draw(st.sampled_from([b"", b"X,y\n1,a\n", b"PK\x03\x04", b"\x00" * 64]))
    return Blob(data), seed, split, not chosen and split == "auto"


def npz_signals(seed: int, n=12, channels=2, steps=5) -> np.ndarray:
    return np.random.default_rng(seed).normal(0, 1e3, (n, channels, steps))


def test_npz_recordings_through_the_timeseries_datamodule(tmp_path, compose_config):
    files = Files(tmp_path)
    cfg = compose_config(["data=recordings_npz", f"data.path={tmp_path / 'rig.npz'}"])

    @examples(FILES["npz"])
    @given(npz_file())
    def check(drawn):
        content, seed, split, clean = drawn
        files.write("rig.npz", content)
        datamodule = files.read(lambda: train_datamodule(cfg, split=split, **LEVELS))
        check_recordings_result(files, datamodule, npz_signals(seed), clean)

    check()
    files.report("npz")


LONG_COLUMNS = ["recording", "time_s", "a_v", "b_v", "label", "split", "force_n"]


@st.composite
def long_table(draw, n_recordings=12, steps=5):
    """Long-table CSV bytes (one row per time step), the clean signals, and the file's settings."""
    chosen = draw(faults(TEXT_FAULTS + ["lengths", "repeated_time", "split_changes", "shuffled"]))
    seed = draw(st.integers(0, 2 ** 16))
    signals = long_table_signals(seed, n_recordings, steps)
    splits = ["train"] * (n_recordings - 4) + ["val", "val", "test", "test"]
    rows = []
    for r in range(n_recordings):
        for k in range(steps):
            rows.append([f"rec{r:02d}", number(k * 0.004), number(signals[r, 0, k]), number(signals[r, 1, k]),
                         ["soft", "hard"][r % 2], splits[r], number([1.0, 10.0, 5.0, 20.0][r % 4])])
    if "lengths" in chosen:  # one recording loses its last steps
        cut = draw(st.integers(0, n_recordings - 1))
        rows = [row for row in rows if not (row[0] == f"rec{cut:02d}" and float(row[1]) > 0.005)]
    if "repeated_time" in chosen:
        for row in rows[:steps]:
            row[1] = "0.0"
    if "split_changes" in chosen:
        rows[1][5] = "test" if rows[1][5] != "test" else "train"
    if "shuffled" in chosen:  # rows in any order are valid: they are sorted by recording and time
        rows = [rows[k] for k in np.random.default_rng(0).permutation(len(rows))]
    content = draw(text_file(LONG_COLUMNS, rows, chosen - {"lengths", "repeated_time", "split_changes", "shuffled"},
                             protected=("recording", "label", "split")))
    split = draw(st.sampled_from(RECORDING_SPLITS))
    source = {"lengths": draw(st.sampled_from(["equal", "crop", "pad"])),
              "force_column": "force_n" if split == "force_level" else draw(st.sampled_from([None, "force_n"]))}
    return content, seed, split, source, chosen <= CLEAN_FAULTS | {"shuffled"} and split == "auto"


def long_table_signals(seed: int, n_recordings=12, steps=5) -> np.ndarray:
    return np.random.default_rng(seed).normal(0, 10, (n_recordings, 2, steps))


def test_long_tables_through_the_timeseries_datamodule(tmp_path, compose_config):
    files = Files(tmp_path)
    cfg = compose_config(["data=recordings_table", f"data.path={tmp_path / 'rig.csv'}",
                          "data.source.channel_columns=[a_v,b_v]", "data.label=label"])

    @examples(FILES["long_table"])
    @given(long_table())
    def check(drawn):
        content, seed, split, source, clean = drawn
        files.write("rig.csv", content)
        datamodule = files.read(lambda: train_datamodule(cfg, split=split, source=source, **LEVELS))
        check_recordings_result(files, datamodule, long_table_signals(seed), clean)

    check()
    files.report("long_table")


# -- frame streams (experiment=capacitive_tracking study.recording.path=...) ------------------
ROWS, COLS, REST = 2, 2, 10


def check_stream(files: Files, stream, frames, clean: bool) -> None:
    if stream is None:
        assert not clean, f"a clean stream was refused: {files.message}"
        return
    assert stream.frames.shape[1:] == (ROWS, COLS) and all_finite(stream.frames, dtype=np.float32)
    if clean:
        np.testing.assert_array_equal(stream.frames, frames)


def frame_values(seed: int, n=14) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 4000, (n, ROWS, COLS)).astype(np.float64)


def test_frame_stream_csv_files_and_lines(tmp_path):
    files, streams = Files(tmp_path), Files(tmp_path)  # streams: the same bytes as standard input

    @examples(FILES["frames_csv"])
    @given(st.data(), st.integers(0, 2 ** 16))
    def check(data, seed):
        chosen = data.draw(faults(sorted(set(TEXT_FAULTS) - {"rename_column", "extra_column"}) + ["comment"]))
        frames = frame_values(seed)
        lines = [[number(v) for v in frame.reshape(-1)] for frame in frames]
        content = data.draw(text_file(lines[0], lines[1:], chosen - {"comment"}))  # no header: line 1 is a frame
        if "comment" in chosen:  # comments and blank lines are skipped, so the file stays clean
            content = b"# rest frames first\n\n" + content
        clean = chosen <= {"comment"}
        path = files.write("frames.csv", content)
        check_stream(files, files.read(lambda: load_frames(path, ROWS, COLS, n_rest_frames=REST)), frames, clean)
        # the same bytes as standard input, line by line (experiment=capacitive_tracking study.recording.path=-)
        text = content.decode("utf-8", errors="replace").splitlines()
        got = streams.read(lambda: np.array(list(frames_from_lines(text, ROWS, COLS))).reshape(-1, ROWS, COLS))
        if got is not None:
            assert all_finite(got, dtype=np.float32)
            if clean:
                np.testing.assert_array_equal(got, frames)

    check()
    print(f"\nframes from lines: {streams.loaded + streams.refused} generated streams ({streams.loaded} read, "
          f"{streams.refused} refused in one line)")
    files.report("frames_csv")


WRONG_SHAPES = [lambda v: v.reshape(-1)[:ROWS * COLS], lambda v: v[:, :1],
                lambda v: v.reshape(len(v), ROWS * COLS)[:, :3], lambda v: v[..., None], lambda v: np.float64(3.0)]


@st.composite
def npy_file(draw, seed) -> tuple[bytes, bool]:
    chosen = draw(st.sets(st.sampled_from(["extreme", "dtype", "shape", "flat", "empty", "object", "truncate",
                                           "not_npy", "few_frames"]), max_size=3))
    frames = frame_values(seed)
    values = frames.copy()
    if "extreme" in chosen:
        values[draw(st.integers(0, len(values) - 1)), 0, draw(st.integers(0, COLS - 1))] = \
            draw(st.sampled_from(EXTREME_FLOATS))
    if "dtype" in chosen:
        kind = draw(st.sampled_from(["float32", "float16", "int16", "uint64", "bool", "complex64", "U4"]))
        with np.errstate(over="ignore", invalid="ignore"):
            values = np.nan_to_num(values).astype(kind) if kind in ("int16", "uint64") else values.astype(kind)
    if "few_frames" in chosen:
        values = values[:draw(st.integers(1, REST - 1))]
    if "empty" in chosen:
        values = values[:0]
    if "flat" in chosen:  # [frames, rows * cols] is a valid layout
        values = values.reshape(len(values), ROWS * COLS)
    if "shape" in chosen:
        values = draw(st.sampled_from(WRONG_SHAPES))(values)
    if "object" in chosen:
        values = np.array([values, "x"], dtype=object)
    buffer = io.BytesIO()
    np.save(buffer, values, allow_pickle=True)
    data = buffer.getvalue()
    if "truncate" in chosen:
        data = data[:draw(st.integers(0, len(data) - 1))]
    if "not_npy" in chosen:
        data = draw(st.sampled_from([b"\x93NUMPY", b"1,2,3,4\n", b"\x00" * 32, b"PK\x03\x04"]))
    return Blob(data), chosen <= {"flat"}


def test_frame_stream_npy_files(tmp_path):
    files = Files(tmp_path)

    @examples(FILES["frames_npy"])
    @given(st.data(), st.integers(0, 2 ** 16))
    def check(data, seed):
        content, clean = data.draw(npy_file(seed))
        path = files.write("frames.npy", content)
        stream = files.read(lambda: load_frames(path, ROWS, COLS, n_rest_frames=REST))
        check_stream(files, stream, frame_values(seed), clean)

    check()
    files.report("frames_npy")


# -- predict.py: malformed models and bad input tables through main(argv) ---------------------
def run_predict(files: Files, model: Path, table: Path, output: Path) -> None:
    """predict.py's main as the command runs it: either exit 0 and a finite output file, or exit
    2, one line on stderr and no output file."""
    output.unlink(missing_ok=True)
    err, out = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
        code = predict_main([f"model={model}", f"input={table}", f"output={output}"])
    if code == 2:
        assert err.getvalue().startswith("error: ") and err.getvalue().count("\n") == 1, err.getvalue()
        assert not output.exists()
        files.refused += 1
        return
    assert code == 0 and not err.getvalue(), err.getvalue()
    files.loaded += 1
    result = pd.read_csv(output)
    numeric = result.drop(columns=[c for c in ("predicted",) if c in result])
    assert len(result) and all_finite(numeric.to_numpy())


BAD_METADATA_VALUES = ["", "[", "null", "[]", "{}", '"a_ohm"', "[1, 2]", '["a_ohm", "a_ohm"]', '["a_ohm"]',
                       '["a_ohm", "b_ohm", "c_ohm"]', "0", "-4", "4.0", "1e9", "abc", "regression", "classification",
                       '["prediction"]', '["probabilities"]', '["prediction", "interval_half_width"]', "\u00e9\n2",
                       json.dumps(["x"] * 3000)]


@st.composite
def onnx_file(draw) -> tuple[bytes, str]:
    kind = draw(st.sampled_from(["regression", "classification"]))
    metadata = regression_metadata() if kind == "regression" else classification_metadata()
    for _ in range(draw(st.integers(1, 3))):
        key = draw(st.sampled_from(sorted(metadata) + ["kind"]))
        if draw(st.booleans()):
            metadata.pop(key, None)
        else:
            metadata[key] = draw(st.sampled_from(BAD_METADATA_VALUES))
    build = regression_model if kind == "regression" else classification_model
    data = build(metadata).SerializeToString()
    damage = draw(st.sampled_from([None, None, None, "truncate", "flip", "empty", "text"]))
    if damage == "truncate":
        data = data[:draw(st.integers(0, len(data) - 1))]
    elif damage == "flip":
        at = draw(st.integers(0, len(data) - 1))
        data = data[:at] + bytes([data[at] ^ 0xFF]) + data[at + 1:]
    elif damage == "empty":
        data = b""
    elif damage == "text":
        data = b"a_ohm,b_ohm\n1,2\n"
    return Blob(data), kind


def ordinary_input(folder: Path) -> Path:
    """One input either kind of tiny model can predict: two channels, two windows' worth of rows."""
    path = folder / "input.csv"
    pd.DataFrame(np.linspace(1.0, 2.0, 2 * WINDOW_STEPS * len(CHANNELS)).reshape(-1, len(CHANNELS)),
                 columns=CHANNELS).to_csv(path, index=False)
    return path


def test_malformed_models_through_predict(tmp_path):
    files = Files(tmp_path)
    table = ordinary_input(tmp_path)

    @examples(FILES["onnx_metadata"])
    @given(onnx_file())
    def check(drawn):
        content, _ = drawn
        run_predict(files, files.write("model.onnx", content), table, tmp_path / "out.csv")

    check()
    files.report("onnx_metadata")


def test_bad_input_tables_through_predict(tmp_path):
    files = Files(tmp_path)
    models = {"regression": save(regression_model(), tmp_path / "reg.onnx"),
              "classification": save(classification_model(), tmp_path / "cls.onnx")}

    @examples(FILES["predict_input"])
    @given(st.data(), st.integers(0, 2 ** 16), st.sampled_from(sorted(models)), st.booleans())
    def check(data, seed, kind, parquet):
        values = np.random.default_rng(seed).uniform(0, 1e3, (2 * WINDOW_STEPS + 1, len(CHANNELS)))
        if parquet:
            content, _ = data.draw(parquet_file(dict(zip(CHANNELS, values.T)), text_columns=()))
            path = files.write("input.parquet", content)
        else:
            rows = [[number(v) for v in row] for row in values]
            path = files.write("input.csv", data.draw(text_file(CHANNELS, rows, data.draw(faults()))))
        run_predict(files, models[kind], path, tmp_path / "out.csv")

    check()
    files.report("predict_input")


# -- what the "thorough" profile found, kept as fixed cases ---------------------------------------
def test_a_float16_group_column_groups_by_its_values(tmp_path, compose_config):
    """pandas cannot group a float16 column ("float16 indexes are not supported", a traceback from
    data/sensor_table.py): a group column that is a target is grouped by its checked float64 values."""
    values = table_values(0, 20)
    table = pa.table({**{c: values[c] for c in TABLE_CHANNELS}, "x_mm": values["x_mm"].astype(np.float16),
                      "pressure_pa": values["pressure_pa"]})
    pq.write_table(table, tmp_path / "rig.parquet")
    datamodule = train_datamodule(table_config(compose_config, tmp_path / "rig.parquet"))
    np.testing.assert_array_equal(datamodule.y[:, 0], values["x_mm"].astype(np.float16))
    assert len(np.unique(datamodule.table.groups)) == len(np.unique(values["x_mm"].astype(np.float16)))


def test_tensor_names_that_are_not_utf8_are_one_line(tmp_path):
    """onnxruntime decodes a dimension's name only when it is read (a UnicodeDecodeError from the
    graph check): every name is read where the error becomes one line."""
    model = tmp_path / "model.onnx"
    model.write_bytes(classification_model().SerializeToString().replace(b"batch", b"bat\xffh"))
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = predict_main([f"model={model}", f"input={ordinary_input(tmp_path)}", f"output={tmp_path / 'o.csv'}"])
    assert code == 2 and err.getvalue() == f"error: {model}: metadata or tensor names are not UTF-8 text; " \
                                           "re-export the run\n"


# -- end to end through the commands ---------------------------------------------------------
def command(script: str, *args, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(ROOT / script), *args], capture_output=True, text=True, cwd=cwd,
                          env={**__import__("os").environ, "CI": "true"})


def assert_refused(result, *fragments) -> None:
    assert result.returncode == 2, result.stderr[-2000:]
    lines = result.stderr.splitlines()
    assert "Traceback" not in result.stderr and lines and lines[-1].startswith("error: "), result.stderr[-2000:]
    assert sum(line.startswith("error: ") for line in lines) == 1
    for fragment in fragments:
        assert fragment in lines[-1], lines[-1]


def test_bad_files_end_to_end_through_train_and_predict(tmp_path):
    """Each command as a user runs it: exit 2, the last stderr line the one error, no traceback,
    and neither a metrics.json nor a model in the failed run's folder."""
    rows = "r_1_ohm,r_2_ohm,r_3_ohm,x_mm,pressure_pa\n" + "".join(f"{100 + k},200,300,{k},1000\n" for k in range(20))
    (tmp_path / "rig.csv").write_bytes(rows.encode()[:150] + b"\xff\xfe\x00")  # truncated, not UTF-8, a NUL
    X = np.random.default_rng(0).normal(size=(8, 2, 5))
    X[3, 1, 2] = 1e308  # finite in float64, inf in the float32 the recordings are kept in
    np.savez(tmp_path / "rig.npz", X=X, y=np.array(["a", "b"] * 4))
    (tmp_path / "frames.csv").write_text("1,2,3,4\n" * 3 + "1,2,1e308,4\n")
    runs = {"table": ["data=table", f"data.path={tmp_path / 'rig.csv'}",
                      "data.channel_columns=[r_1_ohm,r_2_ohm,r_3_ohm]", "data.target_columns=[x_mm,pressure_pa]",
                      "data.group_columns=[x_mm]", "model=extra_trees"],
            "npz": ["data=recordings_npz", f"data.path={tmp_path / 'rig.npz'}", "model=prcnn"],
            "frames": ["experiment=capacitive_tracking", f"study.recording.path={tmp_path / 'frames.csv'}",
                       "study.recording.rows=2", "study.recording.cols=2"]}
    expected = {"table": "rig.csv", "npz": "rig.npz", "frames": "frames.csv: frame 3, cell 2"}
    for name, overrides in runs.items():
        result = command("train.py", *overrides, f"hydra.run.dir={tmp_path / name}", cwd=tmp_path)
        assert_refused(result, expected[name])
        assert (tmp_path / name / "error.txt").is_file()
        assert not (tmp_path / name / "metrics.json").exists() and not (tmp_path / name / "model.onnx").exists()

    pd.DataFrame({"a_ohm": [1.0] * 8, "b_ohm": [1.0, -1e308] + [1.0] * 6}).to_csv(tmp_path / "pass.csv", index=False)
    model = save(classification_model(), tmp_path / "model.onnx")
    assert_refused(command("predict.py", f"model={model}", "input=pass.csv", "output=out.csv", cwd=tmp_path),
                   "pass.csv: ", "'b_ohm'", "line 3", "-1e+308", "float32")
    broken = save(classification_model({**classification_metadata(), "classes": '["soft", "hard"'}),
                  tmp_path / "broken.onnx")
    assert_refused(command("predict.py", f"model={broken}", "input=pass.csv", "output=out.csv", cwd=tmp_path),
                   "broken.onnx: metadata 'classes' is not valid JSON")
    assert not (tmp_path / "out.csv").exists()
