import numpy as np
import pytest

from common.errors import InputError
from data.datamodules.regression import RegressionDataModule, from_table
from data.preprocessing.features import FEATURE_GROUPS
from data.scenes.rubber12 import Rubber12Scene
from data.splits.indices import kfold_indices

ALL = {g: True for g in FEATURE_GROUPS}
CHANNELS = [f"r_{k:02d}_ohm" for k in range(1, 13)]
TARGETS = ["x_mm", "y_mm", "depth_mm", "pressure_pa"]
EFFECTS = {"contact": {}, "percolation": {}, "temperature_drift": {}, "adc": {}}


@pytest.fixture(scope="module")
def scene_table():
    return Rubber12Scene(n_samples=270, effects=EFFECTS, grid_nodes=21, progress=False).generate()


class Fixed:
    """A source that hands out an already generated table."""
    def __init__(self, table):
        self.table = table

    def load(self):
        return self.table


@pytest.mark.parametrize("split", ["random", "grouped"])
def test_splits_are_disjoint_cover_everything_and_hold_out_15_percent(scene_table, split):
    dm = RegressionDataModule(Fixed(scene_table), ALL, split=split, seed=3).setup()
    parts = [dm.train_idx, dm.val_idx, dm.test_idx]
    joined = np.concatenate(parts)
    assert len(joined) == len(set(joined)) == 270
    assert abs(dm.test_idx.size / 270 - 0.15) < 0.05
    if split == "grouped":
        groups = [set(scene_table.groups[p]) for p in parts]
        assert not (groups[0] & groups[1] or groups[0] & groups[2] or groups[1] & groups[2])


def test_scaler_is_fitted_on_training_rows_only(scene_table):
    dm = RegressionDataModule(Fixed(scene_table), ALL, seed=0).setup()
    X_train, y_train = dm.train
    np.testing.assert_allclose(X_train.mean(axis=0), 0.0, atol=1e-9)
    assert np.abs(dm.test[0].mean(axis=0)).max() > 1e-3  # test rows were not used to fit it
    np.testing.assert_array_equal(y_train, scene_table.targets[dm.train_idx])  # targets stay in units


def test_grouped_folds_cover_the_rows_and_keep_each_group_in_one_fold(scene_table):
    groups = scene_table.groups
    folds, warning = kfold_indices(len(groups), 4, seed=0, groups=groups)
    assert len(folds) == 4 and warning is None
    held = np.concatenate([h for _, h in folds])
    assert sorted(held) == list(range(len(groups)))
    for fit, hold in folds:
        assert not set(groups[fit]) & set(groups[hold])


def test_grouped_folds_never_fall_back_to_ungrouped_ones():
    groups = np.repeat([0, 1, 2], 10)
    folds, warning = kfold_indices(30, 5, seed=0, groups=groups)
    assert len(folds) == 3 and "only 3 groups" in warning
    for fit, hold in folds:
        assert np.unique(groups[hold]).size == 1 and not set(groups[fit]) & set(groups[hold])
    with pytest.raises(InputError, match="at least two groups"):
        kfold_indices(30, 5, seed=0, groups=np.zeros(30))


def test_same_seed_same_split(scene_table):
    a = RegressionDataModule(Fixed(scene_table), ALL, seed=5).setup()
    b = RegressionDataModule(Fixed(scene_table), ALL, seed=5).setup()
    np.testing.assert_array_equal(a.test_idx, b.test_idx)
    np.testing.assert_array_equal(a.X, b.X)


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_users_table_gives_the_same_arrays_as_the_scene(scene_table, tmp_path, suffix):
    path = tmp_path / f"rig{suffix}"
    frame = scene_table.frame
    frame.to_csv(path, index=False) if suffix == ".csv" else frame.to_parquet(path)
    from_file = from_table(str(path), CHANNELS, TARGETS, ["x_mm", "y_mm", "depth_mm"],
                           features=ALL, split="grouped", seed=0).setup()
    np.testing.assert_allclose(from_file.table.channels, scene_table.channels, rtol=1e-12)
    np.testing.assert_allclose(from_file.table.targets, scene_table.targets, rtol=1e-12)
    # grouping by press point in the file reproduces the scene's groups (up to their labels)
    pairs = set(zip(from_file.table.groups, scene_table.groups))
    assert len(pairs) == len(np.unique(scene_table.groups)) == 90  # 9 points x 10 depths
    assert from_file.X.shape == (270, 74) and np.isfinite(from_file.X).all()


def write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


@pytest.mark.parametrize("name, text, message", [
    ("empty.csv", "", "file is empty"),
    ("header.csv", "a,b\n", "no rows"),
    ("missing.csv", "r_01_ohm,x_mm\n1,2\n", "missing channel column"),
    ("nan.csv", "r_01_ohm,r_02_ohm,x_mm\n1,,2\n", "'r_02_ohm' has a missing or infinite value in line 2"),
    ("inf.csv", "r_01_ohm,r_02_ohm,x_mm\n1,2,3\n1,inf,3\n", "'r_02_ohm' has a missing or infinite value in line 3"),
    ("text.csv", "r_01_ohm,r_02_ohm,x_mm\n1,2,3\n1,open,3\n", "non-numeric value 'open' in line 3"),
    ("rig.xlsx", "whatever", "unsupported file type"),
])
def test_bad_tables_are_one_line_errors(tmp_path, name, text, message):
    path = write(tmp_path, name, text)
    dm = from_table(path, ["r_01_ohm", "r_02_ohm"], ["x_mm"], features=ALL)
    with pytest.raises(InputError, match=message) as error:
        dm.setup()
    assert "\n" not in str(error.value)


def test_missing_file_is_a_one_line_error(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        from_table(str(tmp_path / "nope.csv"), CHANNELS, TARGETS, features=ALL).setup()
