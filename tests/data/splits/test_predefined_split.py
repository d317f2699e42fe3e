"""data.split=predefined: the train / val / test sides a user's file declares (data/splits/indices.py),
for recordings (NPZ array, long-table column) and regression tables (a split column)."""
import numpy as np
import pandas as pd
import pytest
from hydra.utils import instantiate
from hypothesis import given
from hypothesis import strategies as st

from common.errors import InputError
from data.datamodules.regression import RegressionDataModule
from data.datamodules.timeseries import TimeSeriesDataModule
from data.readers.recording_reader import load_long_table, load_npz
from data.sensor_table import SensorTable
from data.splits.indices import predefined_split

FEATURES_RAW = {"raw": True, "log1p": False, "sqrt": False, "zscore": False, "stats": False,
                "pair_products": False, "pair_ratios": False}


# -- the one implementation -------------------------------------------------------------------
@given(sides=st.lists(st.sampled_from(["train", "test", "val"]), min_size=6, max_size=40),
       seed=st.integers(0, 2 ** 16))
def test_declared_sides_are_kept_and_test_rows_are_only_test(sides, seed):
    sides = ["train", "train", "test"] + sides  # at least two train rows and one test row
    values = np.array(sides)
    train, val, test = predefined_split(values, 0.3, seed, "rig.npz")
    np.testing.assert_array_equal(test, np.flatnonzero(values == "test"))
    assert not set(train) & set(val) and not (set(train) | set(val)) & set(test)
    if (values == "val").any():  # declared validation is used as declared
        np.testing.assert_array_equal(val, np.flatnonzero(values == "val"))
        np.testing.assert_array_equal(train, np.flatnonzero(values == "train"))
    else:  # carved from the train rows only
        assert set(train) | set(val) == set(np.flatnonzero(values == "train")) and len(val) > 0


def test_carved_validation_is_stratified_and_grouped():
    labels = np.repeat(["a", "b"], 20)
    values = np.array((["train"] * 15 + ["test"] * 5) * 2)
    train, val, _ = predefined_split(values, 0.2, 0, "rig.npz", strata=labels)
    assert sorted(np.unique(labels[val], return_counts=True)[1]) == [3, 3]  # 20 % of 15 per class
    groups = np.repeat(np.arange(20), 2)  # pairs of rows are one press point
    values = np.where(groups < 16, "train", "test")
    train, val, test = predefined_split(values, 0.25, 0, "rig.csv", groups=groups)
    assert not set(groups[train]) & set(groups[val]) and len(val) == 8
    again = predefined_split(values, 0.25, 0, "rig.csv", groups=groups)
    np.testing.assert_array_equal(again[1], val)  # same seed, same split


@pytest.mark.parametrize("values, groups, message", [
    (["train", "validation", "test"], None, "rig.npz: split value 'validation' in entry 1 is not one of train, val, test"),
    (["train", "Train ", "val"], None, "rig.npz has no test rows"),
    (["test", "val", "test"], None, "rig.npz has no train rows"),
    (None, None, "data.split=predefined needs a split per row"),
    (["train", "test", "train", "train"], [0, 0, 1, 1], "group 0 has rows labelled test and train"),
    (["train", "test"], None, "rig.npz has 1 train row; validation needs another one"),
])
def test_predefined_mistakes_are_one_line_errors(values, groups, message):
    with pytest.raises(InputError, match=message) as error:
        predefined_split(None if values is None else np.array(values, dtype=object), 0.2, 0, "rig.npz",
                         groups=None if groups is None else np.array(groups))
    assert "\n" not in str(error.value)


# -- recordings ---------------------------------------------------------------------------------
def tones(n=40, steps=100, seed=0):
    """Two classes of 3-channel series told apart by frequency."""
    rng = np.random.default_rng(seed)
    t = np.arange(steps) / 50.0
    y = np.repeat(["slow", "fast"], n // 2)
    X = np.stack([np.stack([np.sin(2 * np.pi * (2.0 if c == "slow" else 6.0) * t + rng.uniform(0, 6))
                            + 0.2 * rng.standard_normal(steps) for _ in range(3)]) for c in y])
    return X.astype(np.float32), y


class Loaded:
    def __init__(self, loader):
        self.loader = loader

    def load(self):
        return self.loader()


def neutral_datamodule(source, **options):
    settings = dict(label="y", decimate=1, window_length=None, window_step=None, trim_start=0, trim_end=0,
                    split="predefined", force_calibration=None, modalities=None, val_fraction=0.25)
    return TimeSeriesDataModule(source, **{**settings, **options})


def test_npz_split_array_decides_train_and_test_recordings(tmp_path):
    X, y = tones()
    split = np.array(["train", "test"] * 20)
    np.savez(tmp_path / "rig.npz", X=X, y=y, split=split)
    dm = neutral_datamodule(Loaded(lambda: load_npz(tmp_path / "rig.npz"))).setup()
    np.testing.assert_array_equal(dm.test_recordings, np.flatnonzero(split == "test"))
    train_side = set(np.flatnonzero(split == "train"))
    assert set(dm.train_recordings) | set(dm.val_recordings) == train_side
    assert len(dm.val_recordings) == 5 and set(y[dm.val_recordings]) == {"slow", "fast"}  # stratified
    summary = dm.summary()
    assert summary["split"] == "predefined" and "train / val / test" in summary["split_note"]
    # the channel statistics come from the training windows only
    np.testing.assert_allclose(dm.channel_mean.ravel(), X[dm.train_recordings].mean(axis=(0, 2)), rtol=1e-4, atol=1e-6)


def test_npz_without_split_or_with_a_bad_value_says_so(tmp_path):
    X, y = tones(n=4)
    np.savez(tmp_path / "plain.npz", X=X, y=y)
    with pytest.raises(InputError, match="needs a split per row: an array 'split' in an NPZ"):
        neutral_datamodule(Loaded(lambda: load_npz(tmp_path / "plain.npz"))).setup()
    np.savez(tmp_path / "typo.npz", X=X, y=y, split=np.array(["train", "tset", "test", "train"]))
    with pytest.raises(InputError, match=r"array 'split': split value 'tset' in split\[1\] is not one of"):
        load_npz(tmp_path / "typo.npz")


def long_table(path, split_of_recording, mixed_recording=None):
    X, y = tones(n=len(split_of_recording), steps=20)
    rows = []
    for r, side in enumerate(split_of_recording):
        for t in range(20):
            value = "test" if r == mixed_recording and t == 7 else side
            rows.append({"recording": f"r{r}", "time_s": t / 50.0, "ax": X[r, 0, t], "ay": X[r, 1, t],
                         "label": y[r], "split": value})
    pd.DataFrame(rows).sample(frac=1.0, random_state=1).to_csv(path, index=False)


def test_long_table_split_column_is_one_value_per_recording(tmp_path):
    sides = ["train", "train", "val", "test"] * 4
    long_table(tmp_path / "rig.csv", sides)
    load = lambda: load_long_table(tmp_path / "rig.csv", "recording", "time_s", ["ax", "ay"], ["label"])
    dm = neutral_datamodule(Loaded(load), label="label").setup()
    order = sorted(f"r{r}" for r in range(16))  # recordings are sorted by id
    declared = np.array([sides[int(name[1:])] for name in order])
    np.testing.assert_array_equal(dm.val_recordings, np.flatnonzero(declared == "val"))
    np.testing.assert_array_equal(dm.test_recordings, np.flatnonzero(declared == "test"))
    assert dm.recording_rate_hz == pytest.approx(50.0)  # from the time column
    long_table(tmp_path / "mixed.csv", sides, mixed_recording=0)
    with pytest.raises(InputError, match="mixed.csv: recording 'r0' has rows labelled test and train"):
        load_long_table(tmp_path / "mixed.csv", "recording", "time_s", ["ax", "ay"], ["label"])


# -- regression tables --------------------------------------------------------------------------
def press_table(path, split_of_group):
    rng = np.random.default_rng(0)
    rows = []
    for group, side in enumerate(split_of_group):
        for repeat in range(3):
            rows.append({"r_ohm": 100 + group + rng.normal(), "s_ohm": 50 + rng.normal(), "x_mm": float(group),
                         "depth_mm": 1.0, "split": side})
    pd.DataFrame(rows).to_csv(path, index=False)
    return pd.DataFrame(rows)


def test_table_split_column_through_the_data_config(compose_config, tmp_path):
    frame = press_table(tmp_path / "rig.csv", ["train"] * 12 + ["test"] * 4)
    cfg = compose_config(["data=table", f"data.path={tmp_path / 'rig.csv'}", "data.channel_columns=[r_ohm,s_ohm]",
                          "data.target_columns=[x_mm]", "data.group_columns=[x_mm]", "data.split=predefined",
                          "data.val_fraction=0.25", "data.calibration_fraction=0.25"])
    dm = instantiate(cfg.data).setup()
    np.testing.assert_array_equal(dm.test_idx, np.flatnonzero(frame["split"] == "test"))
    parts = {"train": dm.train_idx, "val": dm.val_idx, "calibration": dm.cal_idx}
    assert all(len(rows) for rows in parts.values())
    assert set(np.concatenate(list(parts.values()))) == set(np.flatnonzero(frame["split"] == "train"))
    groups = {name: set(frame["x_mm"].to_numpy()[rows]) for name, rows in parts.items()}
    assert not groups["train"] & groups["val"] and not groups["train"] & groups["calibration"]
    assert dm.summary()["split"] == "predefined"


@pytest.mark.parametrize("sides, group_columns, message", [
    (["train"] * 8, "[x_mm]", "rig.csv has no test rows"),
    (["train"] * 6 + ["Test", "valid"], "[x_mm]", "rig.csv: column 'split': split value 'valid' in line 23"),
    (["train"] * 6 + ["test"] * 2, "[depth_mm]", "rig.csv: group 0 has rows labelled test and train"),
])
def test_table_split_mistakes(compose_config, tmp_path, sides, group_columns, message):
    press_table(tmp_path / "rig.csv", sides)
    cfg = compose_config(["data=table", f"data.path={tmp_path / 'rig.csv'}", "data.channel_columns=[r_ohm,s_ohm]",
                          "data.target_columns=[x_mm]", f"data.group_columns={group_columns}",
                          "data.split=predefined"])
    with pytest.raises(InputError, match=message):
        instantiate(cfg.data).setup()


def test_table_without_split_column_cannot_be_predefined(compose_config, tmp_path):
    press_table(tmp_path / "rig.csv", ["train"] * 4 + ["test"] * 2)
    cfg = compose_config(["data=table", f"data.path={tmp_path / 'rig.csv'}", "data.channel_columns=[r_ohm,s_ohm]",
                          "data.target_columns=[x_mm]", "data.group_columns=null", "data.split=predefined",
                          "data.split_column=null"])
    with pytest.raises(InputError, match="data.split=predefined needs a split per row"):
        instantiate(cfg.data).setup()
    with pytest.raises(InputError, match="data.split must be one of auto, random, grouped, predefined, got 'fixed'"):
        RegressionDataModule(Loaded(lambda: None), FEATURES_RAW, split="fixed").setup()


# -- a scene's table carries a split too -----------------------------------------------------------
def test_a_scene_table_can_declare_its_split():
    rng = np.random.default_rng(0)
    frame = pd.DataFrame({"a_ohm": rng.normal(size=12) + 10, "b_ohm": rng.normal(size=12) + 10,
                          "depth_mm": rng.uniform(size=12)})
    split = np.array(["train", "train", "val", "test"] * 3)
    table = SensorTable(frame, ["a_ohm", "b_ohm"], ["depth_mm"], np.arange(12), {"source": "scene", "scene": "demo"},
                        split=split)
    dm = RegressionDataModule(Loaded(lambda: table), FEATURES_RAW, split="predefined", calibration_fraction=0.0).setup()
    np.testing.assert_array_equal(dm.val_idx, np.flatnonzero(split == "val"))
    np.testing.assert_array_equal(dm.test_idx, np.flatnonzero(split == "test"))
    np.testing.assert_array_equal(dm.train_idx, np.flatnonzero(split == "train"))
    with pytest.raises(InputError, match="12 rows"):
        SensorTable(frame, ["a_ohm"], ["depth_mm"], np.arange(12), split=split[:5])
    without = SensorTable(frame, ["a_ohm"], ["depth_mm"], np.arange(12))
    with pytest.raises(InputError, match="demo has none"):
        RegressionDataModule(Loaded(lambda: SensorTable(frame, ["a_ohm"], ["depth_mm"], np.arange(12),
                                                        {"scene": "demo"})),
                             FEATURES_RAW, split="predefined").setup()
    assert without.split is None
