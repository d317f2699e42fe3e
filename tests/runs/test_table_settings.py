"""A user's file needs its path and its target: channels default to every numeric column that is
not a target, a group or the split column; an error about a missing column names the setting
that fixes it; data.path is the one key for a file's path, the older data.source.path a one-line
error naming it."""
import numpy as np
import pandas as pd
import pytest
from hydra.utils import instantiate

from common.errors import InputError
from runs.config_checks import check_config


def write(tmp_path, frame) -> str:
    path = tmp_path / "rig.csv"
    frame.to_csv(path, index=False)
    return str(path)


def rig(n=40) -> pd.DataFrame:
    rng = np.random.default_rng(0)
    return pd.DataFrame({"a_ohm": rng.uniform(900, 1100, n), "note": ["ok"] * n, "b_v": rng.normal(size=n),
                         "site": np.arange(n) % 5, "done": [True] * n, "depth_mm": rng.uniform(0, 2, n),
                         "split": np.where(np.arange(n) % 5 == 4, "test", "train")})   # whole sites on one side


def datamodule(compose_config, path, *overrides):
    return instantiate(compose_config(["data=table", f"data.path={path}", *overrides]).data).setup()


def test_channels_default_to_the_numeric_columns_that_are_not_target_group_or_split(compose_config, tmp_path):
    path = write(tmp_path, rig())
    dm = datamodule(compose_config, path, "data.target_columns=[depth_mm]")
    assert dm.channel_names == ["a_ohm", "b_v", "site"]   # not the text, the booleans, the target or the split
    dm = datamodule(compose_config, path, "data.target_columns=[depth_mm]", "data.group_columns=[site]")
    assert dm.channel_names == ["a_ohm", "b_v"] and len(np.unique(dm.table.groups)) == 5
    chosen = datamodule(compose_config, path, "data.target_columns=[depth_mm]", "data.channel_columns=[b_v,site]")
    assert chosen.channel_names == ["b_v", "site"]


def test_the_table_config_names_no_rubber12_columns(compose_config):
    data = compose_config(["data=table"]).data
    assert data.channel_columns is None and data.group_columns is None and data.task == "auto"
    assert "r_01_ohm" not in str(data) and "x_mm" not in str(data)


@pytest.mark.parametrize("overrides, message", [
    (["data.target_columns=[depth]"], "missing target column(s) depth; found a_ohm, note, b_v, site, done, depth_mm, "
                                      "split; set data.target_columns=[...]"),
    (["data.target_columns=[depth_mm]", "data.channel_columns=[a_ohm,c_ohm]"], "set data.channel_columns=[...]"),
    (["data.target_columns=[depth_mm]", "data.group_columns=[press]"], "missing group column(s) press; "),
    (["data.target_columns=[depth_mm]", "data.channel_columns=[note]"],
     "channel column 'note' has a non-numeric value 'ok' in line 2"),
    (["data.target_columns=[note]", "data.task=regression"],
     "target column 'note' has a non-numeric value 'ok' in line 2; for class labels set data.task=classification"),
    (["data.target_columns=[depth_mm,site]", "data.task=classification"],
     "classification takes one target column (the class label), got 2: depth_mm, site"),
])
def test_a_missing_or_wrong_column_names_the_setting_that_fixes_it(compose_config, tmp_path, overrides, message):
    path = write(tmp_path, rig())
    with pytest.raises(InputError) as error:
        datamodule(compose_config, path, *overrides)
    assert message in str(error.value) and "\n" not in str(error.value)


def test_a_table_without_a_target_setting_says_which_setting(compose_config, tmp_path):
    with pytest.raises(InputError, match=r"^data.target_columns needs a value \(add data.target_columns=...\)$"):
        check_config(compose_config(["data=table", f"data.path={write(tmp_path, rig())}"]))


@pytest.mark.parametrize("data", ["recordings_npz", "recordings_table"])
def test_the_path_key_is_data_path_for_recordings_and_the_old_key_is_named(compose_config, data):
    cfg = compose_config([f"data={data}", "model=prcnn", "data.source.path=rig.npz"])
    with pytest.raises(InputError, match=r"^data.source.path is not a setting: a file's path is data.path for every "
                                         r"data source \(data.path=rig.npz\)$"):
        check_config(cfg)
    with pytest.raises(InputError, match=r"^data.path needs a value \(add data.path=...\)$"):
        check_config(compose_config([f"data={data}", "model=prcnn"]))


def test_recordings_are_read_from_data_path(compose_config, tmp_path):
    rng = np.random.default_rng(0)
    np.savez(tmp_path / "rig.npz", X=rng.normal(size=(12, 2, 30)), y=np.array(["a", "b"] * 6))
    dm = instantiate(compose_config(["data=recordings_npz", f"data.path={tmp_path / 'rig.npz'}", "model=prcnn"]).data)
    assert dm.source.path == str(tmp_path / "rig.npz")
    assert len(dm.setup().classes) == 2
