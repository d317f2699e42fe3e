"""One datamodule for torch nets and scikit-learn trees alike.

    source (a scene or a user's table) -> SensorTable -> physics features -> splits -> scaling

A held-out test split (15 % by default) is never touched in training or selection; an
optional calibration split (for conformal intervals) and a validation split come out of the
rest. A table that declares its rows' sides (a `split` column) is split that way by default
(`split=auto`; `declared_split=ignore` draws instead, data/splits/indices.py: resolve_split); calibration
and (when no val rows are declared) validation are then carved from the train rows, grouped
(predefined_split). Without a declared split, `auto` draws `grouped`.
The table's values were checked when it was built (data/sensor_table.py); the features every model
is given are checked here to be finite in float32, naming the feature.
Features are standardised with statistics from the training split only. Targets stay in
physical units here: a net standardises its own targets inside `fit` and reports back in
units, so every model sees and returns the same arrays.

A classification table (data/sensor_table.py: its one target a class label) goes through the
same steps; `task` says which it is, `y` holds class codes and `classes` their names, and every
class of the validation, calibration and test rows must have training rows (a classifier cannot
learn a class it never sees), checked before any fitting.
"""
import copy
import logging

import numpy as np
from sklearn.preprocessing import StandardScaler

from common.errors import InputError
from common.progress import phase
from common.standardise import constant_columns
from data.preprocessing.features import compute_features, feature_names
from data.readers.table_reader import MODEL_DTYPE, where
from data.sensor_table import SensorTable, TableSource
from data.splits.indices import SPLIT_NOTES, holdout, predefined_split, resolve_split
from data.splits.settings import check_split_settings

log = logging.getLogger("touchstone")
DRAWN_SPLIT = "grouped"      # what split=auto draws when the table declares no split
LARGE_TABLE_ROWS = 100_000   # from here on the features take seconds: their phase is logged


class RegressionDataModule:
    def __init__(self, source, features, split="auto", test_fraction=0.15, val_fraction=0.15,
                 calibration_fraction=0.0, n_folds=5, seed=0, declared_split="use"):
        self.source = source
        self.features = features
        self.split = split   # as asked; setup() replaces auto with the split it used
        self.declared_split = declared_split
        self.test_fraction = test_fraction
        self.val_fraction = val_fraction
        self.calibration_fraction = calibration_fraction
        self.n_folds = n_folds
        self.seed = seed

    def setup(self) -> "RegressionDataModule":
        check_split_settings(self.n_folds, self.test_fraction, self.val_fraction, self.calibration_fraction,
                             self.split)
        table = self.source.load()
        if not isinstance(table, SensorTable):
            name = getattr(self.source, "name", type(self.source).__name__)
            kind = type(table).__name__
            raise InputError(f"scene {name} produces a {kind}, not one row per press; for recordings use "
                             "data=timeseries (experiment=materials10, textures13, combined18), for a contact "
                             "stream experiment=capacitive_tracking")
        self.table = table
        self.task = "classification" if table.classes is not None else "regression"
        self.channel_names = list(table.channel_columns)
        self.target_names = list(table.target_columns)
        self.feature_names = feature_names(self.channel_names, self.features)
        self.y = table.targets
        if self.task == "classification":
            self.classes, self.label = list(table.classes), self.target_names[0]
            self.y = self.y[:, 0].astype(np.int64)

        self.split, self.split_source = resolve_split(self.split, table.split is not None, self.declared_split,
                                                      DRAWN_SPLIT, table.source_name)
        check_split_settings(self.n_folds, self.test_fraction, self.val_fraction, self.calibration_fraction,
                             self.split)
        if self.split == "predefined":
            self._predefined_split(table)
        else:
            self._drawn_split(table)
        log.info("data split: %s; %d train, %d validation, %d calibration, %d test rows", self.split_source,
                 self.train_idx.size, self.val_idx.size, self.cal_idx.size, self.test_idx.size)
        if self.task == "classification":
            self._check_classes()
        with phase(f"features of {len(self.y):,} rows", enabled=len(self.y) >= LARGE_TABLE_ROWS):
            self.X, self.scaler = self.features_for(self.features)
        return self

    def resplit(self, seed: int) -> "RegressionDataModule":
        """The same rows drawn into another train/validation/calibration/test split (the split's
        kind, grouped by default, and fractions as this one's; `seed` draws it) with its own
        scaler: the repeated splits a run's spread is measured over. A declared split has one
        draw only, and is refused."""
        if self.split == "predefined":
            raise InputError(f"{self.table.source_name} declares its split; there is no other split to draw")
        other = copy.copy(self)
        other.seed = seed
        other._drawn_split(self.table)
        other.X, other.scaler = other.features_for(self.features)
        return other

    def _predefined_split(self, table: SensorTable) -> None:
        """The table's declared sides; calibration is carved from its train rows, grouped."""
        where = table.description.get("path", table.description.get("scene", "the table"))
        train, self.val_idx, self.test_idx = predefined_split(table.split, self.val_fraction, self.seed + 1,
                                                              str(where), groups=table.groups)
        self.cal_idx = np.array([], dtype=np.int64)
        if self.calibration_fraction > 0:
            train, self.cal_idx = holdout(train, table.groups, self.calibration_fraction, "grouped", self.seed + 2)
        self.train_idx = train

    def _drawn_split(self, table: SensorTable) -> None:
        everything = np.arange(len(self.y))
        rest, self.test_idx = holdout(everything, table.groups, self.test_fraction, self.split, self.seed)
        # Calibration and validation are fractions of the whole set, taken from what is left.
        left = 1.0 - self.test_fraction
        self.cal_idx = np.array([], dtype=np.int64)
        if self.calibration_fraction > 0:
            rest, self.cal_idx = holdout(rest, table.groups, self.calibration_fraction / left, self.split, self.seed + 2)
            left -= self.calibration_fraction
        self.train_idx, self.val_idx = holdout(rest, table.groups, self.val_fraction / left, self.split, self.seed + 1)

    def _check_classes(self) -> None:
        source = self.table.source_name
        if len(self.classes) < 2:
            raise InputError(f"{source}: every row has {self.label} = {self.classes[0]!r}; classification needs at "
                             "least two classes")
        trained = set(self.y[self.train_idx].tolist())
        for part, rows in (("validation", self.val_idx), ("calibration", self.cal_idx), ("test", self.test_idx)):
            unseen = sorted(set(self.y[rows].tolist()) - trained)
            if unseen:
                raise InputError(f"{source}: class {self.classes[unseen[0]]!r} of {self.label} has {part} rows but no "
                                 f"training rows ({int((self.y == unseen[0]).sum())} row(s) in all); a classifier "
                                 "cannot learn a class it never sees: add rows of it or drop them")

    def features_for(self, groups):
        """Scaled features of every row for a choice of feature groups (used by the ablation):
        the scaler is fitted on the training rows only."""
        features = compute_features(self.table.channels, groups)
        finite = np.isfinite(features).all(axis=1)
        if not finite.all():  # readings like 1e308: finite, but their products and powers are not
            row = int(np.argmin(finite))
            path = self.table.description.get("path")
            place = f"{path}: {where(path, row)}" if path else f"row {row + 1}"
            raise InputError(f"{place}: channel readings {self.table.channels[row].tolist()} overflow the physics "
                             "features (products and powers of readings beyond float64's range)")
        scaler = StandardScaler().fit(features[self.train_idx])
        # A feature constant on the training rows up to rounding (three channels' kurtosis) tells
        # nothing, yet standardising its rounding noise would give the models values of order one
        # that differ between the float64 pipeline and its float32 graph: an infinite scale maps
        # it to exactly 0 in both.
        scaler.scale_[constant_columns(features[self.train_idx])] = np.inf
        scaled = scaler.transform(features)
        with np.errstate(over="ignore"):
            bad = ~np.isfinite(scaled.astype(MODEL_DTYPE))
        if bad.any():  # what the models are given, in the dtype they compute in
            row, column = np.unravel_index(int(np.flatnonzero(bad)[0]), bad.shape)
            name = feature_names(self.channel_names, groups)[column]
            raise InputError(f"{self.table.source_name}: feature '{name}' of {where(self.table.source_name, row)} is "
                             f"{features[row, column]:g}, not finite in float32 once standardised; rescale its channels")
        return scaled, scaler

    def _part(self, idx):
        return self.X[idx], self.y[idx]

    @property
    def train(self):
        return self._part(self.train_idx)

    @property
    def val(self):
        return self._part(self.val_idx)

    @property
    def test(self):
        return self._part(self.test_idx)

    @property
    def calibration_idx(self) -> np.ndarray:
        """The rows intervals and class probabilities are calibrated on: every held-out row that no
        model is fitted on, the calibration split and the validation split, each held out grouped
        as the split is. The validation rows double the calibration groups; on a table of 90 press
        points in groups of 5 repeats (docs/configuration.md, the K-fold blend, seeds 0-5) the
        95 % intervals' test coverage is within noise either way, with a smaller spread over seeds
        on x and y when calibrated on both (x 0.917 ± 0.068 vs 0.898 ± 0.131 alone)."""
        return np.concatenate([self.cal_idx, self.val_idx])

    @property
    def calibration(self):
        return self._part(self.calibration_idx)

    def summary(self) -> dict:
        task = {"task": self.task, "classes": self.classes} if self.task == "classification" else {"task": self.task}
        return {**task, "split": self.split, "split_note": SPLIT_NOTES.get(self.split, ""), "split_source": self.split_source,
                "n_train": int(self.train_idx.size), "n_val": int(self.val_idx.size),
                "n_calibration": int(self.cal_idx.size), "n_test": int(self.test_idx.size), "n_features": len(self.feature_names),
                "channels": self.channel_names, "targets": self.target_names,
                "source": self.table.description}


def from_table(path, channel_columns=None, target_columns=None, group_columns=None, split_column="split", task="auto",
               **datamodule_options) -> RegressionDataModule:
    """`data=table`: a user's CSV/Parquet recording served by the same datamodule as a scene
    (data/sensor_table.py TableSource: default channels, the task from the target's type)."""
    source = TableSource(path, channel_columns, target_columns, group_columns, split_column, task)
    return RegressionDataModule(source, **datamodule_options)
