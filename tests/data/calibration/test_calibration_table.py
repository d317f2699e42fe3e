"""A rig's calibration table: served under the scene's channel names (mapped when the rig names
them otherwise); channels that do not match, missing targets, too few presses, NaN and impossible
values are one-line errors naming the problem."""
import numpy as np
import pytest
from hydra.utils import instantiate

from common.errors import InputError
from data.calibration.calibration_table import CalibrationTableSource
from data.calibration.identifiable import CALIBRATIONS
from data.calibration.press_simulation import channel_names
from data.calibration.rig_standin import rig_presses


@pytest.fixture
def rubber12(compose_config):
    return instantiate(compose_config(["scene=rubber12", "scene.progress=false", "scene.grid_nodes=21"]).scene)


@pytest.fixture
def presses(rubber12):
    return rig_presses(rubber12, {}, 3, 12)


def load(tmp_path, frame, scene, **options):
    path = tmp_path / "presses.csv"
    frame.to_csv(path, index=False)
    return CalibrationTableSource(str(path), scene, **options).load()


def one_line_error(tmp_path, frame, scene, **options) -> str:
    with pytest.raises(InputError) as error:
        load(tmp_path, frame, scene, **options)
    assert "\n" not in str(error.value)
    return str(error.value)


def test_the_table_is_served_under_the_scenes_channels_in_its_order(tmp_path, rubber12, presses):
    shuffled = presses[list(presses.columns[::-1])]
    table = load(tmp_path, shuffled, rubber12)
    assert table.channel_columns == [f"r_{k:02d}_ohm" for k in range(1, 13)]
    assert table.target_columns == ["x_mm", "y_mm", "depth_mm", "pressure_pa"]
    np.testing.assert_allclose(table.channels, presses[table.channel_columns].to_numpy())


@pytest.mark.parametrize("name", sorted(CALIBRATIONS))
def test_the_expected_channels_are_the_scenes_own(compose_config, name):
    scene = instantiate(compose_config([f"scene={name}", "scene.progress=false"]).scene)
    own = {"rubber12": lambda: [f"r_{k:02d}_ohm" for k in range(1, 13)], "taxels": lambda: scene.channel_names(),
           "capacitive6x6": lambda: [f"rmc_r{r}_c{c}" for r in range(scene.rows) for c in range(scene.cols)]}[name]
    assert channel_names(scene) == own()


def test_a_rigs_own_channel_names_are_mapped(tmp_path, rubber12, presses):
    mapping = {f"ch{k}": f"r_{k:02d}_ohm" for k in range(1, 13)}
    renamed = presses.rename(columns={v: k for k, v in mapping.items()})
    table = load(tmp_path, renamed, rubber12, channel_map=mapping)
    np.testing.assert_allclose(table.channels, presses[table.channel_columns].to_numpy())


def test_channels_that_do_not_match_list_the_expected_ones(tmp_path, rubber12, presses):
    message = one_line_error(tmp_path, presses.drop(columns=["r_03_ohm"]), rubber12)
    assert "channels do not match scene rubber12: expected r_01_ohm, r_02_ohm, r_03_ohm" in message
    assert "missing r_03_ohm" in message and "calibration.channel_map" in message
    message = one_line_error(tmp_path, presses, rubber12, channel_map={"r_01_ohm": "r_99_ohm"})
    assert "maps to r_99_ohm, which scene rubber12 does not read" in message


def test_missing_targets_and_too_few_presses_are_refused(tmp_path, rubber12, presses):
    assert "need target column(s) x_mm, y_mm, depth_mm, pressure_pa; missing pressure_pa" in one_line_error(
        tmp_path, presses.drop(columns=["pressure_pa"]), rubber12)
    assert "2 presses; calibrating scene rubber12 needs at least 4" in one_line_error(tmp_path, presses.iloc[:2],
                                                                                        rubber12)


@pytest.mark.parametrize("column, value, words", [("r_05_ohm", np.nan, "'r_05_ohm' has a missing or infinite value"),
                                                  ("r_05_ohm", -120.0, "'r_05_ohm' has -120"),
                                                  ("depth_mm", np.nan, "'depth_mm' has a missing or infinite value")])
def test_nan_and_impossible_values_name_the_column(tmp_path, rubber12, presses, column, value, words):
    bad = presses.copy()
    bad.loc[4, column] = value
    assert words in one_line_error(tmp_path, bad, rubber12)
