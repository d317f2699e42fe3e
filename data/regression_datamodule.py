"""One datamodule for torch nets and scikit-learn trees alike.

    source (a scene or a user's table) -> SensorTable -> physics features -> splits -> scaling

A held-out test split (15 % by default) is never touched in training or selection; an
optional calibration split (for conformal intervals) and a validation split come out of the
rest. With `split=predefined` the table's own split column says which rows are train / val /
test; calibration and (when no val rows are declared) validation are carved from the train rows,
grouped (data/splits.py: predefined_split).
Features are standardised with statistics from the training split only. Targets stay in
physical units here: a net standardises its own targets inside `fit` and reports back in
units, so every model sees and returns the same arrays.
"""
import numpy as np
from sklearn.preprocessing import StandardScaler

from data.features import compute_features, feature_names
from data.split_settings import check_split_settings
from data.splits import SPLIT_NOTES, holdout, predefined_split
from data.errors import InputError
from data.tables import SensorTable, TableSource


class RegressionDataModule:
    def __init__(self, source, features, split="grouped", test_fraction=0.15, val_fraction=0.15,
                 calibration_fraction=0.0, n_folds=5, seed=0):
        self.source = source
        self.features = features
        self.split = split
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
        self.channel_names = list(table.channel_columns)
        self.target_names = list(table.target_columns)
        self.feature_names = feature_names(self.channel_names, self.features)
        self.y = table.targets

        if self.split == "predefined":
            self._predefined_split(table)
        else:
            self._drawn_split(table)
        self.X, self.scaler = self.features_for(self.features)
        return self

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

    def features_for(self, groups):
        """Scaled features of every row for a choice of feature groups (used by the ablation):
        the scaler is fitted on the training rows only."""
        features = compute_features(self.table.channels, groups)
        scaler = StandardScaler().fit(features[self.train_idx])
        return scaler.transform(features), scaler

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
    def calibration(self):
        """The calibration split, or the validation split when none was asked for."""
        return self._part(self.cal_idx if self.cal_idx.size else self.val_idx)

    def summary(self) -> dict:
        return {"split": self.split, "split_note": SPLIT_NOTES.get(self.split, ""), "n_train": int(self.train_idx.size), "n_val": int(self.val_idx.size),
                "n_calibration": int(self.cal_idx.size), "n_test": int(self.test_idx.size), "n_features": len(self.feature_names),
                "channels": self.channel_names, "targets": self.target_names,
                "source": self.table.description}


def from_table(path, channel_columns, target_columns, group_columns=None, split_column="split",
               **datamodule_options):
    """`data=table`: a user's CSV/Parquet recording served by the same datamodule as a scene."""
    source = TableSource(path, channel_columns, target_columns, group_columns, split_column)
    return RegressionDataModule(source, **datamodule_options)
