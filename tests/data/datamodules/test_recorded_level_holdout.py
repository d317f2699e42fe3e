"""`data.recorded_test_fraction`: recordings at the trained force levels held out for test, so
the accuracy at recorded levels is measured on recordings training never saw (the seed paper's
over-fitting observation compares it with the accuracy at unseen levels)."""
import numpy as np
import pytest

from common.errors import InputError
from data.datamodules.timeseries import TimeSeriesDataModule
from data.scenes.fingertip import FingertipScene


def datamodule(**kwargs):
    scene = FingertipScene(boards=["glass/flat", "acrylic/flat"], passes_per_level=5, effects={})
    return TimeSeriesDataModule(scene, label="board", **kwargs).setup()


def test_held_out_recordings_at_trained_levels_go_to_test_and_never_train():
    plain, held = datamodule(), datamodule(recorded_test_fraction=0.4)
    levels = held.recordings.labels["force_level_n"].to_numpy()
    labels = held.recordings.labels["board"].to_numpy()
    assert set(levels[held.test_recordings]) == {1, 5, 10, 15, 20, 25}
    assert not set(held.train_recordings) & set(held.test_recordings)
    assert set(held.val_recordings) == set(plain.val_recordings)          # unseen-level split unchanged
    assert set(plain.train_recordings) == set(held.train_recordings) | (set(held.test_recordings)
                                                                        - set(plain.test_recordings))
    recorded = [r for r in held.test_recordings if levels[r] in (1, 10, 15, 25)]
    for board in ("glass/flat", "acrylic/flat"):                         # 2 of 5 per class and level
        for level in (1, 10, 15, 25):
            assert sum(1 for r in recorded if labels[r] == board and levels[r] == level) == 2
    assert not set(held.train_window_recording) & set(held.test_window_recording)


@pytest.mark.parametrize("fraction", [1.0, -0.1, "half"])
def test_bad_fractions_are_one_line_errors(fraction):
    with pytest.raises(InputError, match="recorded_test_fraction"):
        datamodule(recorded_test_fraction=fraction)


def test_same_seed_same_held_out_recordings():
    assert np.array_equal(datamodule(recorded_test_fraction=0.4).test_recordings,
                          datamodule(recorded_test_fraction=0.4).test_recordings)


def test_too_few_recordings_per_class_and_level_hold_none_out_and_say_so():
    scene = FingertipScene(boards=["glass/flat", "acrylic/flat"], passes_per_level=2, effects={})
    dm = TimeSeriesDataModule(scene, label="board", recorded_test_fraction=0.2).setup()
    levels = dm.recordings.labels["force_level_n"].to_numpy()
    assert set(levels[dm.test_recordings]) == {5, 20}
    assert dm.summary()["recorded_level_test"].startswith("none")
    held = datamodule(recorded_test_fraction=0.4).summary()["recorded_level_test"]
    assert held.startswith("16 recordings")
