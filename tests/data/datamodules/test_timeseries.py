"""Windows, force-level splits, users' recordings and Algorithm 1 (virtual force levels)."""
import numpy as np
import pandas as pd
import pytest

from common.errors import InputError
from data.datamodules.timeseries import TimeSeriesDataModule
from data.physics.force_sensing_resistor import fsr_force_n
from data.preprocessing.virtual_force_levels import virtual_force_levels
from data.preprocessing.windows import cut_windows, decimate
from data.readers.recording_reader import load_long_table, load_npz
from data.scenes.fingertip import FingertipScene


def test_window_counts_trimming_and_variance_filter():
    rng = np.random.default_rng(0)
    recording = np.zeros((1, 2, 100))
    recording[0, 0, 50:] = rng.standard_normal(50)       # flat first half, noisy second half
    windows, owner = cut_windows(recording, length=20, step=10, trim_start=5, trim_end=5)
    assert windows.shape == (8, 2, 20) and (owner == 0).all()   # (90 - 20) / 10 + 1
    np.testing.assert_array_equal(windows[1, 0], recording[0, 0, 15:35])
    kept, _ = cut_windows(recording, length=20, step=10, trim_start=5, trim_end=5, min_variance=0.1)
    assert len(kept) == 4  # windows starting at 45 or later see the noise; 35 has only 5 noisy steps of 20
    with pytest.raises(InputError, match="shorter than the window length"):
        cut_windows(recording, length=95, step=1, trim_start=5, trim_end=5)


def test_decimate_takes_block_means():
    x = np.arange(10.0)[None, None]
    np.testing.assert_array_equal(decimate(x, 3), [[[1.0, 4.0, 7.0]]])


def small_scene(**kwargs):
    return FingertipScene(**{"boards": ["glass/flat", "acrylic/flat", "resin/circular_5mm"], "passes_per_level": 2,
                             "effects": {}, **kwargs})


CALIBRATION = {"channel": "piezoresistive_v", "supply_v": 3.3, "reference_v": 0.25, "feedback_resistor_ohm": 1.8e4,
               "series_resistor_ohm": 1.0e3,
               "fsr_resistance_1n_ohm": 1.0e4, "fsr_exponent": 0.9, "fsr_saturation_n": 22.0}


def test_force_level_split_never_leaks_a_level():
    dm = TimeSeriesDataModule(small_scene(), label="board", force_calibration=CALIBRATION).setup()
    levels = dm.recordings.labels["force_level_n"].to_numpy()
    assert set(levels[dm.train_window_recording]) == {1, 10, 15, 25}
    assert set(levels[dm.val_window_recording]) == set(levels[dm.test_window_recording]) == {5, 20}
    assert not set(levels[dm.train_window_recording]) & set(levels[dm.test_window_recording])
    assert not set(dm.train_window_recording) & set(dm.val_window_recording)
    with pytest.raises(InputError, match="share"):
        TimeSeriesDataModule(small_scene(), label="board", train_levels=[1, 5], val_levels=[5]).setup()
    with pytest.raises(InputError, match="were not recorded"):
        TimeSeriesDataModule(small_scene(), label="board", train_levels=[1, 2], val_levels=[5]).setup()


def sides(dm):
    return {"train": dm.train_window_recording, "val": dm.val_window_recording, "test": dm.test_window_recording}


def test_validation_and_test_divide_the_unseen_levels_by_recording():
    dm = TimeSeriesDataModule(small_scene(), label="board").setup()
    labels = dm.recordings.labels
    windows = sides(dm)
    # every recording is on exactly one side, and all of its windows with it
    recordings = {side: set(owner.tolist()) for side, owner in windows.items()}
    assert not recordings["train"] & recordings["val"] and not recordings["train"] & recordings["test"]
    assert not recordings["val"] & recordings["test"]
    assert recordings["train"] | recordings["val"] | recordings["test"] == set(range(len(labels)))
    assert recordings["val"] == set(dm.val_recordings) and recordings["test"] == set(dm.test_recordings)
    # half of the 12 unseen-level recordings each side, one per board and level (2 passes each)
    assert len(dm.val_recordings) == len(dm.test_recordings) == 6
    for side in ("val", "test"):
        strata = labels.iloc[sorted(recordings[side])][["board", "force_level_n"]]
        assert not strata.duplicated().any() and len(strata) == 6
    summary = dm.summary()
    assert summary["n_test_recordings"] == 6 and summary["n_test_windows"] == len(dm.y_test) > 0
    assert summary["test_stratified_by"] == ["board", "force_level_n"]
    # seeded: the same seed gives the same division
    again = TimeSeriesDataModule(small_scene(), label="board").setup()
    np.testing.assert_array_equal(again.test_recordings, dm.test_recordings)


def test_test_windows_are_scaled_with_training_statistics():
    dm = TimeSeriesDataModule(small_scene(), label="board").setup()
    signals = decimate(dm.recordings.signals[dm.test_recordings], 10)
    raw, owner = cut_windows(signals, 140, 20, 3, 3)
    np.testing.assert_allclose(dm.X_test * dm.channel_std + dm.channel_mean, raw, rtol=1e-5, atol=1e-5)
    np.testing.assert_array_equal(dm.test_window_recording, dm.test_recordings[owner])
    X_test, y_test = dm.test
    assert X_test.dtype == np.float32 and y_test.dtype == np.int64 and len(X_test) == len(y_test)
    real_train = dm.X_train * dm.channel_std + dm.channel_mean
    np.testing.assert_allclose(real_train.mean(axis=(0, 2)), dm.channel_mean.ravel(), rtol=1e-4, atol=1e-6)


def test_one_pass_per_level_falls_back_to_stratifying_by_label():
    # one recording per board and level: no (board, level) stratum can go to both sides
    dm = TimeSeriesDataModule(small_scene(passes_per_level=1), label="board").setup()
    labels = dm.recordings.labels
    assert dm.summary()["test_stratified_by"] == ["board"]
    assert sorted(labels["board"][dm.val_recordings]) == sorted(labels["board"][dm.test_recordings])
    assert len(dm.val_recordings) == len(dm.test_recordings) == 3


def test_stratified_split_holds_out_test_before_validation():
    dm = TimeSeriesDataModule(small_scene(passes_per_level=2), label="board", split="stratified",
                              test_fraction=0.25, val_fraction=0.2).setup()
    labels = dm.recordings.labels
    recordings = {side: set(owner.tolist()) for side, owner in sides(dm).items()}
    assert not recordings["train"] & recordings["val"] and not recordings["train"] & recordings["test"]
    assert not recordings["val"] & recordings["test"]
    assert recordings["train"] | recordings["val"] | recordings["test"] == set(range(len(labels)))
    assert len(dm.test_recordings) == 9                                  # a quarter of 36
    assert len(dm.val_recordings) == 6                                   # a fifth of the other 27, rounded up
    for side in (dm.val_recordings, dm.test_recordings):                 # every board on each side
        assert set(labels["board"][side]) == set(labels["board"])


@pytest.mark.parametrize("kwargs, message", [
    ({"test_fraction": 0.0}, r"data.test_fraction must be a number in \(0, 1\), got 0.0"),
    ({"test_fraction": 1.0}, r"data.test_fraction must be a number in \(0, 1\), got 1.0"),
    ({"test_fraction": "half"}, r"data.test_fraction must be a number in \(0, 1\), got 'half'"),
    ({"test_fraction": None}, r"data.test_fraction must be a number in \(0, 1\), got None"),
    ({"split": "stratified", "val_fraction": 1.5}, r"data.val_fraction must be a number in \(0, 1\)"),
    ({"boards": ["glass/flat"], "val_levels": [5]}, r"1 recording\(s\) at data.val_levels \[5\] N; validation and test"),
    ({"boards": ["glass/flat"], "test_fraction": 0.9}, "leaves validation or test without a recording of the 2"),
    ({"split": "stratified", "test_fraction": 0.9}, "data.split=stratified: "),
])
def test_bad_test_splits_are_one_line_errors(kwargs, message):
    scene_kwargs = {"passes_per_level": 1, **({"boards": kwargs.pop("boards")} if "boards" in kwargs else {})}
    with pytest.raises(InputError, match=message) as error:
        TimeSeriesDataModule(small_scene(**scene_kwargs), label="board", **kwargs).setup()
    assert "\n" not in str(error.value)


def test_virtual_windows_come_from_training_recordings_only(monkeypatch):
    import data.datamodules.timeseries as module
    seen = {}

    def spy(windows, labels, levels, target_levels, **kwargs):
        seen.update(windows=windows.copy(), levels=levels.copy())
        return virtual_force_levels(windows, labels, levels, target_levels, **kwargs)

    monkeypatch.setattr(module, "virtual_force_levels", spy)
    augment = {"enabled": True, "target_levels": [5, 20], "triboelectric_channel": "triboelectric_na",
               "piezoresistive_channel": "piezoresistive_n"}
    dm = TimeSeriesDataModule(small_scene(), label="board", force_calibration=CALIBRATION, augment=augment).setup()
    # Algorithm 1 was handed exactly the real training windows (unscaled), none at 5 or 20 N
    real_train = dm.X_train[:len(dm.train_window_recording)] * dm.channel_std + dm.channel_mean
    np.testing.assert_allclose(seen["windows"], real_train, rtol=1e-5, atol=1e-5)
    assert set(seen["levels"]) == {1, 10, 15, 25} and dm.n_virtual_windows > 0
    assert len(dm.X_train) == len(dm.train_window_recording) + dm.n_virtual_windows


def test_fsr_calibration_reads_the_force_level():
    scene = small_scene(boards=["glass/flat"], force_levels_n=[1, 5, 25], passes_per_level=1)
    recordings = scene.generate()
    newtons = fsr_force_n(recordings.channel("piezoresistive_v"), fsr_saturation_n=22.0)
    np.testing.assert_allclose(newtons.max(axis=1), [1, 5, 25], rtol=0.01)


def test_modalities_accept_any_groups_of_channels():
    dm = TimeSeriesDataModule(small_scene(), label="material",
                              modalities={"charge": ["triboelectric_na"], "load": [1]}).setup()
    assert dm.modality_channels == {"charge": [0], "load": [1]}
    with pytest.raises(InputError, match="unknown channel 'gyro'"):
        TimeSeriesDataModule(small_scene(), label="material", modalities={"imu": ["gyro"]}).setup()


def test_users_npz_and_long_table_load_as_recordings(tmp_path):
    X = np.random.default_rng(0).standard_normal((6, 3, 50)).astype(np.float32)
    np.savez(tmp_path / "rig.npz", X=X, y=np.array(list("aabbcc")), force_level=np.array([1, 5, 1, 5, 1, 5.0]))
    recordings = load_npz(tmp_path / "rig.npz", label="surface")
    np.testing.assert_array_equal(recordings.signals, X)
    assert list(recordings.labels["surface"]) == list("aabbcc")
    rows = [{"rec": r, "t": t, "ax": X[r, 0, t], "ay": X[r, 1, t], "az": X[r, 2, t], "surface": "abc"[r // 2]}
            for r in range(6) for t in range(50)]
    pd.DataFrame(rows).sample(frac=1, random_state=0).to_csv(tmp_path / "long.csv", index=False)
    table = load_long_table(tmp_path / "long.csv", "rec", "t", ["ax", "ay", "az"], ["surface"])
    np.testing.assert_allclose(table.signals, X, rtol=1e-6)


@pytest.mark.parametrize("arrays, message", [
    ({"X": np.zeros((2, 3))}, "missing array 'y'"),
    ({"X": np.zeros((2, 3)), "y": np.zeros(2)}, r"X must be \(n, channels, length\)"),
    ({"X": np.zeros((2, 1, 5)), "y": np.zeros(3)}, "3 labels for 2 recordings"),
    ({"X": np.full((2, 1, 5), np.nan), "y": np.zeros(2)}, "NaN or inf"),
])
def test_bad_npz_files_are_one_line_errors(tmp_path, arrays, message):
    np.savez(tmp_path / "bad.npz", **arrays)
    with pytest.raises(InputError, match=message):
        load_npz(tmp_path / "bad.npz")


def hand_built(levels=(1.0, 2.0, 4.0, 8.0), te_values=None):
    """One window per level of class 0; TE is constant (so f1 = |TE|), PR peaks at the level."""
    te_values = te_values if te_values is not None else [1 + 0.5 * d for d in levels]  # f1 = 1 + f3 / 2
    windows = np.zeros((len(levels), 2, 5))
    for k, (d, te) in enumerate(zip(levels, te_values)):
        windows[k, 0] = te
        windows[k, 1] = [0, d / 2, d, d / 2, 0]
    return windows, np.zeros(len(levels), dtype=int), np.asarray(levels)


def test_algorithm_1_gives_the_exact_scaled_windows():
    windows, labels, levels = hand_built()
    virtual, virtual_labels, virtual_levels, report = virtual_force_levels(windows, labels, levels, [3.0])
    # neighbours of 3 N are 2 N and 4 N; F(3) = 1 + 3/2 = 2.5 exactly (the cubic fit of a line)
    assert report["targets"][3.0]["neighbours"] == [2.0, 4.0]
    expected = windows[[1, 2]].copy()
    expected[:, 0] *= (2.5 / np.array([2.0, 3.0]))[:, None]
    expected[:, 1] *= (3.0 / np.array([2.0, 4.0]))[:, None]
    np.testing.assert_allclose(virtual, expected, rtol=1e-10)
    assert virtual_levels.tolist() == [3.0, 3.0] and virtual_labels.tolist() == [0, 0]
    assert virtual[:, 1].max(axis=1).tolist() == pytest.approx([3.0, 3.0])


def test_algorithm_1_degenerate_cases_are_defined():
    windows, labels, levels = hand_built()
    with pytest.raises(InputError, match="outside the recorded levels"):
        virtual_force_levels(windows, labels, levels, [9.0])
    with pytest.raises(InputError, match="outside the recorded levels"):
        virtual_force_levels(windows, labels, levels, [1.0])  # no recorded level below 1 N
    # two distinct f3 values: the fit drops to a line instead of a singular cubic
    two, two_labels, two_levels = hand_built(levels=(2.0, 4.0))
    virtual, *_ = virtual_force_levels(two, two_labels, two_levels, [3.0])
    assert np.isfinite(virtual).all() and len(virtual) == 2
    # identical f3 everywhere: no curve can be fitted
    same, same_labels, _ = hand_built(levels=(4.0, 4.0))
    with pytest.raises(InputError, match="same f3"):
        virtual_force_levels(same, same_labels, np.array([2.0, 6.0]), [3.0])
    # f1 = 0 and f3 = 0 windows are skipped and counted, never turned into NaN
    zero, zero_labels, zero_levels = hand_built(te_values=[0.0, 2.0, 3.0, 5.0])
    zero[3, 1] = 0.0
    virtual, _, _, report = virtual_force_levels(zero, zero_labels, zero_levels, [3.0])
    assert report["skipped_windows_zero_f1_or_f3"] == 2 and np.isfinite(virtual).all()
    # a cubic that dips to F(target) <= 0 (here F(3) = -0.19) skips the class instead of making
    # negative scales
    dipping, dipping_labels, dipping_levels = hand_built(te_values=[1.0, 0.05, 0.05, 1.0])
    virtual, _, _, report = virtual_force_levels(dipping, dipping_labels, dipping_levels, [3.0])
    assert len(virtual) == 0 and report["targets"][3.0]["skipped_classes"] == ["0"]


def test_users_npz_trains_through_hydra(compose_config, tmp_path):
    from runs.run import run
    rng = np.random.default_rng(0)
    t = np.arange(200) / 50.0
    X = np.stack([np.stack([np.sin(2 * np.pi * f * t) + 0.3 * rng.standard_normal(200),
                            rng.standard_normal(200)]) for f in np.repeat([1.0, 3.0, 6.0], 20)])
    np.savez(tmp_path / "rig.npz", X=X, y=np.repeat(["slow", "mid", "fast"], 20))
    cfg = compose_config(["experiment=materials10", "data=recordings_npz", f"data.path={tmp_path / 'rig.npz'}",
                          "data.label=y", "data.window_length=100", "data.window_step=50", "data.trim_start=0",
                          "data.trim_end=0", "trainer.max_epochs=8", "trainer.lr_milestones=[6]",
                          "trainer.progress=false", "trainer.device=cpu"])
    metrics = run(cfg, tmp_path / "run")
    assert metrics["data"]["classes"] == ["fast", "mid", "slow"]
    assert metrics["val"]["accuracy"] > 0.6  # chance is 1/3
    assert metrics["data"]["n_test_recordings"] == 12  # data.test_fraction=0.2 of 60 (recordings_npz)
    assert metrics["test"]["accuracy"] > 0.6
