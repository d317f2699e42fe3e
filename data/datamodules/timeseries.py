"""The time-series datamodule: recordings -> calibrated channels -> windows -> splits -> scaling.

Serves the surface-recognition models (PR-CNN and its baselines). Every preprocessing step is
an explicit option, neutral in the configs of a user's recordings (configs/data/base/timeseries.yaml)
and set to the seed paper's values by the fingertip's (configs/data/fingertip.yaml):
- recordings come from a scene (fingertip) or a user's NPZ / long table;
- `force_calibration` turns the piezoresistive divider voltage into newtons (Algorithm 1
  compares the channel's maximum with force levels in newtons); null: channels as recorded;
- recordings are decimated (`decimate`, 1: none), trimmed (`trim_start`/`trim_end`, 0: none)
  and cut into windows (data/preprocessing/windows.py); `window_length: null` takes each recording whole;
- `split=auto` (the default) uses the split the recordings declare (an NPZ's `split` array, a
  table's split column) and draws `stratified` when they declare none; `declared_split=ignore`
  draws instead (data/splits/indices.py: resolve_split). The run logs which split it used;
- `split=force_level` trains on the recorded levels (paper: 1, 10, 15, 25 N); the recordings at
  levels never used in training (5, 20 N) are divided by recording into validation (to choose
  with) and test (to report on), `test_fraction` of them to test. `split=stratified` holds out
  `test_fraction` of all recordings for test, then `val_fraction` of the rest for validation,
  stratified by label. `split=predefined` takes the recordings' own train / val / test labels (an
  NPZ's `split` array, a table's split column), carving validation from the train recordings
  (stratified by label, never a class's last training recording, so a set with one or two
  recordings per class trains; data/splits/indices.py) when none are declared. Nets that choose
  their epochs on folds (trainer=reference) pool training and validation recordings again
  (models/timeseries_classifier.py). Windows of one recording always stay on one side;
- `modalities` name groups of channels (names or indices), e.g. triboelectric: [0];
  any number of groups and channels per group, so an IMU's accelerometer + gyroscope fit too;
- `augment` with `enabled: true` adds virtual force-level windows (Algorithm 1) to training;
- channels are standardised with statistics of the real training windows (validation and test
  with the same ones).
Before any training: the label has no missing value, there are at least two classes, training
has at least two, and every class in validation or test has training windows (a model cannot
learn a class it never sees, and would otherwise fail after the whole training); the windows
the networks are given are finite in float32, naming the channel.
"""
import logging

import numpy as np
from sklearn.model_selection import ShuffleSplit, StratifiedShuffleSplit

from common.errors import InputError
from data.physics.force_sensing_resistor import calibrated_channel_name, fsr_force_n
from data.preprocessing.virtual_force_levels import virtual_force_levels
from data.preprocessing.windows import cut_windows, decimate
from data.recording_set import RecordingSet
from data.splits.indices import AUTO, SPLIT_NOTES, predefined_split, resolve_split, split_values

log = logging.getLogger(__name__)


SPLITS = (AUTO, "force_level", "stratified", "predefined")
DRAWN_SPLIT = "stratified"   # what split=auto draws when the recordings declare no split


def _check_fraction(name, value) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 < value < 1.0:
        raise InputError(f"data.{name} must be a number in (0, 1), got {value!r}")


def _check_steps(name, value, may_be_null=False) -> None:
    if value is None and may_be_null:
        return
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise InputError(f"data.{name} must be a whole number of steps >= 1{' or null' if may_be_null else ''}, "
                         f"got {value!r}")


class TimeSeriesDataModule:
    task = "classification"

    def __init__(self, source, label="material", modalities=None, decimate=10, window_length=140,
                 window_step=20, trim_start=3, trim_end=3, min_variance=0.0, variance_channel=0,
                 split="force_level", train_levels=(1, 10, 15, 25), val_levels=(5, 20), val_fraction=0.2,
                 test_fraction=0.5, recorded_test_fraction=0.0, force_calibration=None, augment=None, seed=0,
                 declared_split="use"):
        self.source = source
        self.label = label
        self.modalities = modalities
        self.decimate = decimate
        self.window_length = window_length
        self.window_step = window_step
        self.trim_start = trim_start
        self.trim_end = trim_end
        self.min_variance = min_variance
        self.variance_channel = variance_channel
        self.split = split   # as asked; setup() replaces auto with the split it used
        self.declared_split = declared_split
        self.train_levels = train_levels
        self.val_levels = val_levels
        self.val_fraction = val_fraction
        self.test_fraction = test_fraction
        self.recorded_test_fraction = recorded_test_fraction
        self.force_calibration = force_calibration
        self.augment = augment
        self.seed = seed

    # -- steps ------------------------------------------------------------------------------
    def _load(self) -> RecordingSet:
        _check_steps("decimate", self.decimate)
        _check_steps("window_length", self.window_length, may_be_null=True)
        _check_steps("window_step", self.window_step, may_be_null=True)
        recordings = self.source.load()
        if not isinstance(recordings, RecordingSet):
            raise InputError("data=timeseries needs a scene or file of time-series recordings (e.g. scene=fingertip)")
        if self.label == "split":
            raise InputError("data.label 'split' names the declared train / val / test sides, not a class label")
        # A few raw windows as recorded (before calibration and decimation): what a deployed
        # model receives, kept for latency measurements of the exported pipeline.
        start = self.trim_start * self.decimate
        length = (self.window_length * self.decimate if self.window_length is not None
                  else (recordings.signals.shape[-1] // self.decimate - self.trim_start - self.trim_end) * self.decimate)
        self.raw_examples = recordings.signals[:256, :, start:start + max(length, 0)].copy()
        if self.label not in recordings.labels:
            raise InputError(f"data.label '{self.label}' is not a label of these recordings; "
                             f"available: {', '.join(recordings.labels.columns)}")
        missing = recordings.labels[self.label].isna().to_numpy()
        if missing.any():
            raise InputError(f"{self._where(recordings.description)}: label '{self.label}' of recording "
                             f"{int(np.flatnonzero(missing)[0])} is missing (NaN)")
        if self.force_calibration:
            calibration = dict(self.force_calibration)
            channel = calibration.pop("channel")
            if channel not in recordings.channel_names:
                raise InputError(f"data.force_calibration.channel '{channel}' is not a channel; "
                                 f"available: {', '.join(recordings.channel_names)}")
            k = recordings.channel_names.index(channel)
            recordings.channel_names[k] = calibrated_channel_name(channel, calibration.pop("renamed", None))
            recordings.signals[:, k] = fsr_force_n(recordings.signals[:, k], **calibration)
        return recordings

    @staticmethod
    def _where(description: dict) -> str:
        """How error messages name the recordings: their file, else their scene."""
        return str(description.get("path", description.get("scene", "the recordings")))

    def _check_classes_trained(self, y_train, sides) -> None:
        """There are two classes or more, training has two, and every class that validation or
        test hold has training windows."""
        if len(self.classes) < 2:
            raise InputError(f"{self._where(self.recordings_description)}: every recording has {self.label} = "
                             f"'{self.classes[0]}'; classification needs at least two classes")
        trained = set(np.unique(y_train).tolist())
        if len(trained) < 2:
            names = ", ".join(self.classes[c] for c in sorted(trained)) or "none"
            raise InputError(f"{self._where(self.recordings_description)}: the training windows of data.split="
                             f"{self.split} hold one class ({names}); classification needs at least two")
        for side, y in sides.items():
            unseen = sorted(set(np.unique(y).tolist()) - trained)
            if unseen:
                name = self.classes[unseen[0]]
                raise InputError(f"{self._where(self.recordings_description)}: class '{name}' has "
                                 f"{int((y == unseen[0]).sum())} "
                                 f"{side} window(s) but none in training (data.split={self.split}); a model cannot "
                                 "learn a class it never sees (add training recordings of it, or leave it out)")

    def _check_finite(self, X, names) -> None:
        """(windows, channels, steps) in float32, the channel statistics or the standardised
        windows the networks take, are finite: a channel of readings near 1e20 has a variance
        beyond float32 (3.4e38), which would turn it into zeros or NaN."""
        bad = ~np.isfinite(X)
        if bad.any():
            _, channel, _ = np.unravel_index(int(np.flatnonzero(bad)[0]), X.shape)
            raise InputError(f"{self._where(self.recordings_description)}: channel '{names[channel]}' overflows "
                             "float32 when standardised (its readings are too large: their variance exceeds 3.4e38); "
                             "rescale it")

    def _channel_index(self, channel, names) -> int:
        if isinstance(channel, int) or str(channel).isdigit():
            index = int(channel)
            if not 0 <= index < len(names):
                raise InputError(f"channel index {index} out of range for {len(names)} channels")
            return index
        if channel not in names:
            raise InputError(f"unknown channel '{channel}'; available: {', '.join(names)}")
        return names.index(channel)

    def _divide_unseen(self, rows, labels):
        """Recordings at the unseen levels -> (validation, test, strata used), by recording.

        Stratified by label and force level where every stratum has enough recordings, else by
        label, else a plain seeded shuffle: training never sees either side, so a coarser
        stratification costs balance, never honesty.
        """
        if len(rows) < 2:
            raise InputError(f"data.split=force_level: {len(rows)} recording(s) at data.val_levels "
                             f"{list(self.val_levels)} N; validation and test need at least one each")
        label = labels[self.label].astype(str).to_numpy()[rows]
        label_and_level = np.array([f"{c}|{d}" for c, d in zip(label, labels["force_level_n"].to_numpy()[rows])])
        for strata, key in (([self.label, "force_level_n"], label_and_level), ([self.label], label)):
            try:
                splitter = StratifiedShuffleSplit(n_splits=1, test_size=self.test_fraction, random_state=self.seed)
                val, test = next(splitter.split(np.zeros(len(rows)), key))
                return rows[val], rows[test], strata
            except ValueError:  # a stratum with one recording, or fewer test slots than strata
                continue
        try:
            val, test = next(ShuffleSplit(n_splits=1, test_size=self.test_fraction,
                                          random_state=self.seed).split(rows))
        except ValueError:  # the share rounds one side down to no recording
            raise InputError(f"data.test_fraction={self.test_fraction} leaves validation or test without a "
                             f"recording of the {len(rows)} at data.val_levels") from None
        return rows[val], rows[test], []

    def _hold_out_recorded(self, rows, labels):
        """Recordings at the trained levels -> (train, test): `recorded_test_fraction` of them,
        stratified by label and level, go to test, so the accuracy at recorded levels is measured
        on recordings training never saw (the paper's over-fitting observation compares it with
        the unseen levels'); 0: all train."""
        fraction = self.recorded_test_fraction
        self.recorded_test = None
        if not fraction:
            return rows, rows[:0]
        _check_fraction("recorded_test_fraction", fraction)
        key = np.array([f"{c}|{d}" for c, d in zip(labels[self.label].astype(str).to_numpy()[rows],
                                                     labels["force_level_n"].to_numpy()[rows])])
        try:
            train, test = next(StratifiedShuffleSplit(n_splits=1, test_size=fraction, random_state=self.seed)
                               .split(np.zeros(len(rows)), key))
        except ValueError:  # too few recordings per class and level (a tiny run): hold none out, say so
            self.recorded_test = "none: too few recordings per class and level for the requested share"
            log.warning("data.recorded_test_fraction=%s: %s", fraction, self.recorded_test)
            return rows, rows[:0]
        self.recorded_test = f"{len(test)} recordings at the trained levels, stratified by label and level"
        return np.sort(rows[train]), rows[test]

    def _split_recordings(self, labels):
        """(train, validation, test) recording indices; every window follows its recording."""
        self.validation_carved = False
        if self.split in ("force_level", "stratified"):  # predefined: the data say which are test
            _check_fraction("test_fraction", self.test_fraction)
        if self.split == "force_level":
            if "force_level_n" not in labels:
                raise InputError("data.split=force_level needs a force level per recording")
            levels = labels["force_level_n"].to_numpy()
            train, val = set(map(float, self.train_levels)), set(map(float, self.val_levels))
            if train & val:
                raise InputError(f"data.train_levels and data.val_levels share {sorted(train & val)}")
            missing = (train | val) - set(levels.tolist())
            if missing:
                raise InputError(f"force level(s) {sorted(missing)} N were not recorded; recorded: "
                                 f"{sorted(set(levels.tolist()))}")
            unseen = np.flatnonzero(np.isin(levels, list(val)))
            val_rec, test_rec, self.test_stratified_by = self._divide_unseen(unseen, labels)
            train_rec, recorded_test = self._hold_out_recorded(np.flatnonzero(np.isin(levels, list(train))), labels)
            return train_rec, np.sort(val_rec), np.sort(np.concatenate([test_rec, recorded_test]))
        if self.split == "stratified":
            _check_fraction("val_fraction", self.val_fraction)
            # Stratified by label, never falling back: a class missing from training is not a split.
            classes = labels[self.label].astype(str).to_numpy()
            try:
                rest, test = next(StratifiedShuffleSplit(n_splits=1, test_size=self.test_fraction,
                                                         random_state=self.seed).split(np.zeros(len(classes)), classes))
                train, val = next(StratifiedShuffleSplit(n_splits=1, test_size=self.val_fraction,
                                                         random_state=self.seed).split(rest, classes[rest]))
            except ValueError as error:  # too few recordings per class for the requested shares
                raise InputError(f"data.split=stratified: {error}") from None
            self.test_stratified_by = [self.label]
            return np.sort(rest[train]), np.sort(rest[val]), np.sort(test)
        if self.split == "predefined":
            # Each recording is its own group, so validation is carved by recording, stratified by label.
            where = self._where(self.recordings_description)
            declared = labels["split"].to_numpy() if "split" in labels else None
            self.test_stratified_by = None  # declared by the data, not drawn here
            train, val, test = predefined_split(declared, self.val_fraction, self.seed, str(where),
                                                strata=labels[self.label].astype(str).to_numpy())
            # Validation carved from the declared training recordings (none declared 'val'): the
            # default model may train on them and score on held-out predictions (runs/classification.py).
            self.validation_carved = "val" not in set(split_values(declared, str(where)).tolist())
            return train, val, test
        raise InputError(f"data.split must be one of {', '.join(SPLITS)}, got '{self.split}'")

    def setup(self) -> "TimeSeriesDataModule":
        if self.split not in SPLITS:
            raise InputError(f"data.split must be one of {', '.join(SPLITS)}, got '{self.split}'")
        recordings = self._load()
        self.recordings_description = dict(recordings.description)
        names = list(recordings.channel_names)
        signals = decimate(recordings.signals, int(self.decimate))
        # The rate the recordings were made at (what a deployed model receives) and the rate the
        # networks see after decimation; None when the data do not say.
        self.recording_rate_hz = recordings.sample_rate_hz
        self.sample_rate_hz = None if recordings.sample_rate_hz is None else recordings.sample_rate_hz / int(self.decimate)
        labels = recordings.labels
        self.classes = sorted(labels[self.label].astype(str).unique())
        codes = labels[self.label].astype(str).map({c: i for i, c in enumerate(self.classes)}).to_numpy()
        self.split, self.split_source = resolve_split(self.split, "split" in labels, self.declared_split, DRAWN_SPLIT,
                                                      self._where(recordings.description))
        train_rec, val_rec, test_rec = self._split_recordings(labels)
        self.train_recordings, self.val_recordings, self.test_recordings = train_rec, val_rec, test_rec
        log.info("data split: %s; %d train, %d validation, %d test recordings", self.split_source, len(train_rec),
                 len(val_rec), len(test_rec))

        def windows_of(rows):
            if len(rows) == 0:  # no validation recordings (every class has one training recording)
                X, owner = windows_of(np.arange(1))[0][:0], np.zeros(0, dtype=np.int64)
            else:
                X, owner = cut_windows(signals[rows], self.window_length, self.window_step, self.trim_start,
                                       self.trim_end, self.min_variance, self.variance_channel)
            levels = labels["force_level_n"].to_numpy()[rows][owner] if "force_level_n" in labels else None
            return X, codes[rows][owner], levels, rows[owner]

        X_train, y_train, levels_train, self.train_window_recording = windows_of(train_rec)
        self.train_levels_per_window = levels_train
        X_val, y_val, self.val_levels_per_window, self.val_window_recording = windows_of(val_rec)
        X_test, y_test, self.test_levels_per_window, self.test_window_recording = windows_of(test_rec)
        self._check_classes_trained(y_train, {"validation": y_val, "test": y_test})
        self.augment_report = None
        # Virtual force levels are made from training windows only: validation and test stay unseen.
        if self.augment and self.augment.get("enabled", False):
            if levels_train is None:
                raise InputError("augment=virtual_force_levels needs a force level per recording")
            te = self._channel_index(self.augment["triboelectric_channel"], names)
            pr = self._channel_index(self.augment["piezoresistive_channel"], names)
            virtual, virtual_y, virtual_levels, report = virtual_force_levels(
                X_train, y_train, levels_train, self.augment["target_levels"], te=te, pr=pr)
            self.augment_report = report
            self.n_virtual_windows = len(virtual)
            X_real = X_train
            X_train = np.concatenate([X_train, virtual])
            y_train = np.concatenate([y_train, virtual_y])
        else:
            X_real = X_train
            self.n_virtual_windows = 0

        # Standardise each channel with the real training windows' statistics.
        with np.errstate(over="ignore", invalid="ignore"):  # overflow is reported by name below
            self.channel_mean = X_real.mean(axis=(0, 2), keepdims=True)
            std = X_real.std(axis=(0, 2), keepdims=True)
            self.channel_std = np.where(std > 0, std, 1.0)
            self.X_train = ((X_train - self.channel_mean) / self.channel_std).astype(np.float32)
            self.X_val = ((X_val - self.channel_mean) / self.channel_std).astype(np.float32)
            self.X_test = ((X_test - self.channel_mean) / self.channel_std).astype(np.float32)
        self._check_finite(np.concatenate([self.channel_mean, std], axis=2), names)
        for X in (self.X_train, self.X_val, self.X_test):
            self._check_finite(X, names)
        self.y_train, self.y_val, self.y_test = y_train.astype(np.int64), y_val.astype(np.int64), y_test.astype(np.int64)
        self.channel_names = names
        groups = self.modalities or {name: [name] for name in names}
        if not isinstance(groups, dict) or not all(isinstance(c, (list, tuple)) and len(c) for c in groups.values()):
            raise InputError("data.modalities must map each group name to a non-empty list of channels (names or "
                             f"indices), e.g. {{accel: [0, 1, 2], gyro: [3, 4, 5]}}; got {groups!r}")
        self.modality_channels = {g: [self._channel_index(c, names) for c in chs] for g, chs in groups.items()}
        used = [c for chs in self.modality_channels.values() for c in chs]
        if len(set(used)) != len(used):
            raise InputError(f"data.modalities list a channel twice: {dict(groups)}")
        self.recordings = recordings
        return self

    @property
    def train(self):
        return self.X_train, self.y_train

    @property
    def val(self):
        return self.X_val, self.y_val

    @property
    def test(self):
        """Held-out windows for reporting only: nothing is chosen on them."""
        return self.X_test, self.y_test

    def summary(self) -> dict:
        return {"task": self.task, "label": self.label, "classes": self.classes, "split": self.split,
                "split_note": SPLIT_NOTES.get(self.split, ""), "split_source": self.split_source,
                "train_levels": list(self.train_levels) if self.split == "force_level" else None,
                "val_levels": list(self.val_levels) if self.split == "force_level" else None,
                "n_train_windows": int(len(self.y_train)), "n_virtual_windows": int(self.n_virtual_windows),
                "n_val_windows": int(len(self.y_val)), "n_test_windows": int(len(self.y_test)),
                "n_train_recordings": int(len(self.train_recordings)),
                "n_val_recordings": int(len(self.val_recordings)), "n_test_recordings": int(len(self.test_recordings)),
                "test_fraction": None if self.split == "predefined" else self.test_fraction,
                "test_stratified_by": self.test_stratified_by,
                "recorded_level_test": getattr(self, "recorded_test", None),
                "window": [int(self.X_train.shape[1]), int(self.X_train.shape[2])],
                "sample_rate_hz": self.sample_rate_hz, "recording_rate_hz": self.recording_rate_hz,
                "decimate": int(self.decimate), "trim": [int(self.trim_start), int(self.trim_end)],
                "window_length": self.window_length, "force_calibration": bool(self.force_calibration),
                "channels": self.channel_names,
                "modalities": self.modality_channels, "augment": self.augment_report,
                "source": self.recordings.description}
