"""Every bad training input is one line naming the file, column or key and the problem, raised
while the data are set up (before any training): in-process through the datamodules as train.py
builds them, and a few end to end through train.py (exit code 2, no metrics.json). A split the
data declare is the split unless data.declared_split=ignore; a large table shows progress."""
import json
import logging
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate

from common.errors import InputError
from data.readers.recording_reader import load_long_table
from data.sensor_table import TableSource
from data.units import physical_range

ROOT = Path(__file__).resolve().parents[2]
CHANNELS = [f"r_{k:02d}_ohm" for k in range(1, 5)]
TARGETS = ["x_mm", "depth_mm", "pressure_pa"]


def press_table(n=40, seed=0) -> pd.DataFrame:
    """A valid table of presses: 4 resistances, a signed position, depth and pressure."""
    rng = np.random.default_rng(seed)
    frame = pd.DataFrame({c: 1000.0 + 100.0 * rng.random(n) for c in CHANNELS})
    frame["x_mm"] = rng.integers(-5, 5, n) * 2.0
    frame["depth_mm"] = rng.integers(1, 4, n) * 0.5
    frame["pressure_pa"] = 1000.0 * rng.random(n)
    return frame


def table_datamodule(compose_config, path, *overrides):
    cfg = compose_config(["data=table", f"data.path={path}", f"data.channel_columns=[{','.join(CHANNELS)}]",
                          f"data.target_columns=[{','.join(TARGETS)}]", "data.group_columns=[x_mm,depth_mm]",
                          *overrides])
    return instantiate(cfg.data)


def one_line_error(setup) -> str:
    with pytest.raises(InputError) as error:
        setup()
    message = str(error.value)
    assert "\n" not in message and "Traceback" not in message
    return message


# -- tables of presses --------------------------------------------------------------------------
@pytest.mark.parametrize("column, value, expected", [
    ("r_03_ohm", 1e308, "channel column 'r_03_ohm' has 1e+308 in line 7, beyond the largest float32 (3.403e+38)"),
    ("pressure_pa", 1e308, "target column 'pressure_pa' has 1e+308 in line 7, beyond the largest float32"),
    ("r_02_ohm", 4e38, "channel column 'r_02_ohm' has 4e+38 in line 7, beyond the largest float32"),  # finite in float64
    ("r_03_ohm", -5.0, "channel column 'r_03_ohm' has -5 in line 7; a resistance is >= 0"),
    ("depth_mm", -0.5, "target column 'depth_mm' has -0.5 in line 7; a length is >= 0"),
    ("pressure_pa", -1.0, "target column 'pressure_pa' has -1 in line 7; a pressure is >= 0"),
])
def test_bad_values_in_a_table_name_column_line_and_limit(compose_config, tmp_path, column, value, expected):
    frame = press_table()
    frame.loc[5, column] = value
    frame.to_csv(tmp_path / "rig.csv", index=False)
    message = one_line_error(table_datamodule(compose_config, tmp_path / "rig.csv").setup)
    assert message.startswith(f"{tmp_path / 'rig.csv'}: {expected}"), message


def test_signed_quantities_and_differences_are_accepted(compose_config, tmp_path):
    frame = press_table()
    frame["x_mm"] -= 100.0                         # positions are coordinates
    frame["shear_x_n"] = np.linspace(-1, 1, len(frame))
    frame["delta_r_ohm"] = np.linspace(-50, 50, len(frame))  # a change of resistance
    frame.to_csv(tmp_path / "rig.csv", index=False)
    dm = table_datamodule(compose_config, tmp_path / "rig.csv",
                          f"data.channel_columns=[{','.join(CHANNELS)},delta_r_ohm]",
                          "data.target_columns=[x_mm,shear_x_n]").setup()
    assert dm.y[:, 1].min() == -1.0 and dm.table.channels[:, -1].min() == -50.0


@pytest.mark.parametrize("kind, suffix, expected", [
    ("bool", ".csv", "holds booleans (True/False), not numbers in its unit; refused rather than cast"),
    ("bool", ".parquet", "holds booleans (True/False), not numbers in its unit; refused rather than cast"),
    ("datetime", ".parquet", "holds dates or times, not numbers in its unit; refused rather than cast"),
    ("datetime", ".csv", "has a non-numeric value '2024-01-01 00:00:00' in line 2"),  # a CSV date is text
])
def test_boolean_and_datetime_targets_are_refused_not_cast(compose_config, tmp_path, kind, suffix, expected):
    frame = press_table()
    frame["x_mm"] = frame["x_mm"] > 0 if kind == "bool" else pd.date_range("2024-01-01", periods=len(frame), freq="h")
    path = tmp_path / f"rig{suffix}"
    frame.to_csv(path, index=False) if suffix == ".csv" else frame.to_parquet(path)
    message = one_line_error(table_datamodule(compose_config, path).setup)
    assert message.startswith(f"{path}: target column 'x_mm' {expected}"), message


def test_complex_numbers_are_refused_in_every_reader(tmp_path):
    frame = press_table()
    frame["x_mm"] = frame["x_mm"] + 1j
    frame.to_csv(tmp_path / "rig.csv", index=False)  # written as text such as (-4+1j)
    message = one_line_error(TableSource(tmp_path / "rig.csv", CHANNELS, TARGETS).load)
    assert "target column 'x_mm' has a non-numeric value" in message and "j" in message
    X, y = tones(n=8)
    np.savez(tmp_path / "x.npz", X=X + 1j, y=y)
    assert one_line_error(npz_datamodule(tmp_path / "x.npz").setup) == \
        f"{tmp_path / 'x.npz'}: X must be real numbers (integers or floats), got dtype complex128"
    np.savez(tmp_path / "y.npz", X=X, y=np.arange(8) + 1j)
    assert one_line_error(npz_datamodule(tmp_path / "y.npz").setup) == \
        f"{tmp_path / 'y.npz'}: y holds complex numbers; labels are class names or numbers"


def test_no_channels_and_a_channel_that_is_also_a_target(compose_config, tmp_path):
    press_table().to_csv(tmp_path / "rig.csv", index=False)
    message = one_line_error(table_datamodule(compose_config, tmp_path / "rig.csv", "data.channel_columns=[]").setup)
    assert message == f"{tmp_path / 'rig.csv'}: no channel columns (data.channel_columns is empty)"
    message = one_line_error(table_datamodule(compose_config, tmp_path / "rig.csv",
                                              "data.channel_columns=[r_01_ohm,x_mm]").setup)
    assert "column(s) x_mm listed as both channel and target" in message


# -- recordings -----------------------------------------------------------------------------------
def tones(n=24, steps=60, channels=2, classes=("slow", "fast"), seed=0):
    """`channels`-channel series whose class sets their frequency."""
    rng = np.random.default_rng(seed)
    y = np.array([classes[k % len(classes)] for k in range(n)])
    t = np.arange(steps) / 50.0
    frequency = {c: 2.0 + 4.0 * k for k, c in enumerate(classes)}
    X = np.stack([[np.sin(2 * np.pi * frequency[c] * t + rng.uniform(0, 6)) + 0.1 * rng.standard_normal(steps)
                   for _ in range(channels)] for c in y])
    return X, y


def npz_datamodule(path, *overrides):
    """data=recordings_npz as train.py composes it (its defaults: split=auto, declared_split=use)."""
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose(config_name="config", overrides=["data=recordings_npz", f"data.path={path}", *overrides])
    return instantiate(cfg.data)


def with_value(X, flat_index, value):
    X = X.copy()
    X.flat[flat_index] = value
    return X


SIDE = np.arange(24)  # recording numbers of tones(): classes alternate slow, fast


@pytest.mark.parametrize("arrays, expected", [
    (lambda X, y: {"X": X, "y": np.full(24, "slow")},
     "every recording has y = 'slow'; classification needs at least two classes"),
    (lambda X, y: {"X": X[:, :0], "y": y}, "no channels (signals of shape (24, 0, 60))"),
    (lambda X, y: {"X": with_value(X, 65, 1e308), "y": y},   # recording 0, channel 1, step 5
     "channel 'channel_1' of recording 0 at step 5 is 1e+308, beyond the largest float32 (3.403e+38)"),
    (lambda X, y: {"X": X * 1e20, "y": y},   # finite in float32, but not its variance
     "channel 'channel_0' overflows float32 when standardised"),
    (lambda X, y: {"X": X, "y": y, "channel_names": np.array(["r_a_ohm", "v_b_v"])},
     "channel 'r_a_ohm' of recording 0 at step 0 is "),
    (lambda X, y: {"X": X, "y": SIDE.astype("datetime64[D]")}, "y holds dates or times"),
    (lambda X, y: {"X": X, "y": np.where(SIDE < 18, y, "rough"), "split": np.where(SIDE < 18, "train", "test")},
     "class 'rough' has 6 test window(s) but none in training (data.split=predefined); a model cannot learn"),
    (lambda X, y: {"X": X, "y": np.where((SIDE >= 16) & (SIDE < 20), "rough", y),
                   "split": np.select([SIDE < 16, SIDE < 20], ["train", "val"], "test")},
     "class 'rough' has 4 validation window(s) but none in training"),
    (lambda X, y: {"X": X, "y": y, "split": np.where(SIDE % 2 == 0, "train", "test")},
     "the training windows of data.split=predefined hold one class (slow); classification needs at least two"),
])
def test_bad_recordings_are_one_line_before_training(tmp_path, arrays, expected):
    X, y = tones()
    np.savez(tmp_path / "rig.npz", **arrays(X, y))
    message = one_line_error(npz_datamodule(tmp_path / "rig.npz").setup)
    assert message.startswith(f"{tmp_path / 'rig.npz'}: {expected}"), message


def test_recordings_in_their_physical_range_load(tmp_path):
    X, y = tones()
    np.savez(tmp_path / "rig.npz", X=X + 2.0, y=y, channel_names=np.array(["r_a_ohm", "v_b_v"]))
    assert npz_datamodule(tmp_path / "rig.npz").setup().channel_names == ["r_a_ohm", "v_b_v"]
    np.savez(tmp_path / "rig.npz", X=X, y=y, channel_names=np.array(["r_a_ohm", "v_b_v"]))
    assert "; a resistance is >= 0" in one_line_error(npz_datamodule(tmp_path / "rig.npz").setup)


def long_table(path, n=8, steps=20, edit=None):
    """A long table of recordings (one row per step), `edit(frame)` changing it before saving."""
    X, y = tones(n=n, steps=steps)
    rows = [{"recording": f"r{r}", "time_s": t / 50.0, "ax": X[r, 0, t], "ay": X[r, 1, t], "label": y[r],
             "force_n": 1.0 + r % 2, "level": 1.0 + r % 2} for r in range(n) for t in range(steps)]
    frame = pd.DataFrame(rows)
    if edit:
        edit(frame)
    frame.to_csv(path, index=False)
    return path


def set_cell(row, column, value):
    def edit(frame):
        frame[column] = frame[column].astype(object)
        frame.loc[row, column] = value
    return edit


@pytest.mark.parametrize("edit, force_column, expected", [
    (set_cell(0, "label", np.nan), None, "label column 'label' is empty in line 2; every row needs its recording's label"),
    (set_cell(45, "label", np.nan), None, "label column 'label' is empty in line 47"),
    (set_cell(45, "label", "fast"), None,  # row 45 is step 5 of recording r2, a "slow" one
     "column 'label': recording 'r2' has rows labelled fast and slow; all rows of one recording must carry one label"),
    (set_cell(3, "force_n", 5.0), "force_n",
     "column 'force_n': recording 'r0' has rows labelled 1.0 and 5.0; all rows of one recording must carry one force level"),
    (set_cell(3, "force_n", -1.0), "force_n", "force level column 'force_n' has -1 in line 5; a force is >= 0"),
    (set_cell(3, "level", -1.0), "level", "force level column 'level' has -1 in line 5; a force level in newtons is >= 0"),
    (set_cell(3, "recording", np.nan), None, "recording column 'recording' is empty in line 5"),
    (set_cell(3, "ax", 1e39), None, "channel/time column 'ax' has 1e+39 in line 5, beyond the largest float32"),
])
def test_bad_long_tables_name_the_line(tmp_path, edit, force_column, expected):
    path = long_table(tmp_path / "rig.csv", edit=edit)
    message = one_line_error(lambda: load_long_table(path, "recording", "time_s", ["ax", "ay"], ["label"],
                                                     force_column=force_column))
    assert message.startswith(f"{path}: {expected}"), message


def test_long_table_without_channels(tmp_path):
    path = long_table(tmp_path / "rig.csv")
    assert one_line_error(lambda: load_long_table(path, "recording", "time_s", [], ["label"])) == \
        "data.source.channel_columns is empty: name at least one channel column"


# -- a declared split is the split --------------------------------------------------------------
def test_an_npz_split_is_used_by_default_and_the_run_says_so(tmp_path, caplog):
    X, y = tones(n=24)
    split = np.array(["train"] * 16 + ["test"] * 8)
    np.savez(tmp_path / "rig.npz", X=X, y=y, split=split)
    with caplog.at_level(logging.INFO):
        dm = npz_datamodule(tmp_path / "rig.npz").setup()   # no data.split given
    np.testing.assert_array_equal(dm.test_recordings, np.arange(16, 24))
    assert set(dm.train_recordings) | set(dm.val_recordings) == set(range(16))
    summary = dm.summary()
    assert summary["split"] == "predefined" and f"the train / val / test split {tmp_path / 'rig.npz'} declares" \
        in summary["split_source"]
    assert any(r.getMessage().startswith("data split: the train / val / test split") and "8 test recordings"
               in r.getMessage() for r in caplog.records)

    ignored = npz_datamodule(tmp_path / "rig.npz", "data.declared_split=ignore").setup()
    assert ignored.summary()["split"] == "stratified" and "is ignored (data.declared_split=ignore)" in \
        ignored.summary()["split_source"]
    assert set(ignored.test_recordings) != set(range(16, 24))  # drawn: stratified by label, not the declared side
    message = one_line_error(npz_datamodule(tmp_path / "rig.npz", "data.split=stratified").setup)
    assert message == (f"{tmp_path / 'rig.npz'} declares its own train / val / test split, but data.split=stratified "
                       "asks to draw one; leave data.split at auto to use the declared split, or set "
                       "data.declared_split=ignore to draw stratified")
    message = one_line_error(npz_datamodule(tmp_path / "rig.npz", "data.split=predefined",
                                            "data.declared_split=ignore").setup)
    assert "data.split=predefined uses the split the data declare, which data.declared_split=ignore ignores" in message
    np.savez(tmp_path / "plain.npz", X=X, y=y)
    plain = npz_datamodule(tmp_path / "plain.npz").setup().summary()
    assert plain["split"] == "stratified" and "declares no split" in plain["split_source"]


def test_a_table_split_column_is_used_by_default(compose_config, tmp_path):
    frame = press_table()
    frame["split"] = np.where(frame["x_mm"] >= 4, "test", "train")
    frame.to_csv(tmp_path / "rig.csv", index=False)
    dm = table_datamodule(compose_config, tmp_path / "rig.csv").setup()
    assert dm.split == "predefined"
    np.testing.assert_array_equal(dm.test_idx, np.flatnonzero(frame["split"] == "test"))
    drawn = table_datamodule(compose_config, tmp_path / "rig.csv", "data.declared_split=ignore").setup()
    assert drawn.split == "grouped" and "ignored" in drawn.summary()["split_source"]
    message = one_line_error(table_datamodule(compose_config, tmp_path / "rig.csv", "data.split=random").setup)
    assert "declares its own train / val / test split, but data.split=random asks to draw one" in message
    message = one_line_error(table_datamodule(compose_config, tmp_path / "rig.csv", "data.declared_split=maybe").setup)
    assert message == "data.declared_split must be one of use, ignore, got 'maybe'"


# -- progress on large inputs -------------------------------------------------------------------
def test_reading_a_table_says_so_at_once_and_counts_rows(tmp_path, caplog, monkeypatch):
    import data.readers.table_reader as table_files
    monkeypatch.setenv("CI", "true")  # log lines, as in a run's log, not a terminal bar
    monkeypatch.setattr(table_files, "CSV_CHUNK_ROWS", 7)  # several chunks
    press_table(n=40).to_csv(tmp_path / "rig.csv", index=False)
    with caplog.at_level(logging.INFO, logger="touchstone"):
        frame = table_files.read_table_file(tmp_path / "rig.csv")
    lines = [r.getMessage() for r in caplog.records]
    assert len(frame) == 40 and list(frame.index) == list(range(40))
    assert lines[0].startswith("reading rig.csv (") and lines[0].endswith(" MB) ...")
    assert lines[1].startswith("reading rig.csv (") and ": 40 rows in " in lines[1]


# -- units: the scenes' columns are never refused -----------------------------------------------
@pytest.mark.parametrize("column, quantity", [
    ("r_01_ohm", "resistance"), ("R_01_Ohm", "resistance"), ("c_pf", "capacitance"), ("pressure_pa", "pressure"),
    ("pressure_kpa", "pressure"), ("depth_mm", "length"), ("thickness_um", "length"), ("force_n", "force"),
    ("force2_n", "force"), ("force_level_n", "force"), ("grip_force_n", "force"),
    ("x_mm", None), ("shear_x_n", None), ("normal_n", None), ("force_x_n", None), ("dv_a01_b02_m03_v", None),
    ("delta_r_ohm", None), ("r_change_ohm", None), ("rmc_r0_c3", None), ("rmc_window_r-1_c+0", None),
    ("r_01_norm", None), ("triboelectric_na", None), ("piezoresistive_v", None), ("time_s", None), ("label", None),
])
def test_unit_rules_by_name(column, quantity):
    rule = physical_range(column)
    assert (rule.quantity if rule else None) == quantity
    if rule:
        assert rule.low == 0.0 and rule.why


@pytest.mark.parametrize("scene", ["rubber12", "rubber12_lab", "capacitive6x6_minimal", "taxels", "fingertip_minimal"])
def test_simulated_data_pass_the_same_checks(compose_config, tmp_path, scene):
    """A scene's output is checked when it is built (SensorTable, RecordingSet), and a scene's
    table saved as a user's CSV passes the table reader's checks too."""
    cfg = compose_config([f"scene={scene}"])
    options = {"n_samples": 60} if "n_samples" in cfg.scene else {}
    data = instantiate(cfg.scene, **options).generate()
    if hasattr(data, "frame"):
        data.frame.to_csv(tmp_path / "scene.csv", index=False)
        again = TableSource(tmp_path / "scene.csv", data.channel_columns, data.target_columns).load()
        np.testing.assert_allclose(again.targets, data.targets)


# -- end to end through train.py ----------------------------------------------------------------
def train(tmp_path, *overrides):
    run_dir = tmp_path / "run"
    result = subprocess.run([sys.executable, str(ROOT / "train.py"), *overrides, "export=none",
                             f"hydra.run.dir={run_dir}"], capture_output=True, text=True, cwd=tmp_path,
                            timeout=300, env={**os.environ, "CI": "true"})
    return result, run_dir


def test_train_py_refuses_an_overflowing_channel_in_one_line(tmp_path):
    frame = press_table()
    frame.loc[5, "r_03_ohm"] = 1e308
    frame.to_csv(tmp_path / "rig.csv", index=False)
    result, run_dir = train(tmp_path, "data=table", f"data.path={tmp_path / 'rig.csv'}", "model=extra_trees",
                            f"data.channel_columns=[{','.join(CHANNELS)}]", f"data.target_columns=[{','.join(TARGETS)}]",
                            "data.group_columns=null")
    assert result.returncode == 2, result.stderr[-2000:]
    assert result.stderr == (f"error: {tmp_path / 'rig.csv'}: channel column 'r_03_ohm' has 1e+308 in line 7, beyond "
                             "the largest float32 (3.403e+38): the models compute in float32, where it is infinite\n")
    assert not (run_dir / "metrics.json").exists() and (run_dir / "error.txt").exists()


def test_train_py_refuses_recordings_of_one_class_before_training(tmp_path):
    X, y = tones()
    np.savez(tmp_path / "rig.npz", X=X, y=np.full(len(y), "glass"))
    result, run_dir = train(tmp_path, "data=recordings_npz", f"data.path={tmp_path / 'rig.npz'}", "model=prcnn")
    assert result.returncode == 2, result.stderr[-2000:]
    assert result.stderr == (f"error: {tmp_path / 'rig.npz'}: every recording has y = 'glass'; classification "
                             "needs at least two classes\n")
    assert "epoch" not in (run_dir / "train.log").read_text()  # refused before the first epoch
    assert not (run_dir / "metrics.json").exists()


def test_train_py_keeps_a_tables_declared_test_rows(tmp_path):
    frame = press_table(n=60)
    frame["split"] = np.where(np.arange(60) >= 45, "test", "train")
    frame.to_csv(tmp_path / "rig.csv", index=False)
    result, run_dir = train(tmp_path, "data=table", f"data.path={tmp_path / 'rig.csv'}", "model=decision_tree",
                            f"data.channel_columns=[{','.join(CHANNELS)}]", f"data.target_columns=[{','.join(TARGETS)}]",
                            "data.group_columns=null")
    assert result.returncode == 0, result.stderr[-2000:]
    data = json.loads((run_dir / "metrics.json").read_text())["data"]
    assert data["split"] == "predefined" and data["n_test"] == 15 and "declares" in data["split_source"]
    assert "data split: the train / val / test split" in (run_dir / "train.log").read_text()
