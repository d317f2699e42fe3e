"""One datamodule for torch nets and scikit-learn trees alike.

    source (a scene or a user's table) -> SensorTable -> physics features -> splits -> scaling

A held-out test split (15 % by default) is never touched in training or selection; a
validation split comes out of the rest; fold indices for K-fold cover the training split.
Features are standardised with statistics from the training split only. Targets stay in
physical units here: a net standardises its own targets inside `fit` and reports back in
units, so every model sees and returns the same arrays.
"""
import numpy as np
from sklearn.preprocessing import StandardScaler

from data.features import compute_features, feature_names
from data.splits import fold_indices, holdout
from data.errors import InputError
from data.table import SensorTable, TableSource


class RegressionDataModule:
    def __init__(self, source, features, split="random", test_fraction=0.15, val_fraction=0.15,
                 n_folds=5, seed=0):
        self.source = source
        self.features = features
        self.split = split
        self.test_fraction = test_fraction
        self.val_fraction = val_fraction
        self.n_folds = n_folds
        self.seed = seed

    def setup(self) -> "RegressionDataModule":
        table = self.source.load()
        if not isinstance(table, SensorTable):
            name = getattr(self.source, "name", type(self.source).__name__)
            raise InputError(f"scene {name} produces time-series recordings, not one row per press; "
                             "the regression datamodule needs a tabular scene such as rubber12")
        self.table = table
        self.channel_names = list(table.channel_columns)
        self.target_names = list(table.target_columns)
        self.feature_names = feature_names(self.channel_names, self.features)
        features = compute_features(table.channels, self.features)
        targets = table.targets

        everything = np.arange(len(targets))
        rest, self.test_idx = holdout(everything, table.groups, self.test_fraction, self.split, self.seed)
        # Validation is a fraction of the whole set, taken from what the test split left.
        val_share = self.val_fraction / (1.0 - self.test_fraction)
        self.train_idx, self.val_idx = holdout(rest, table.groups, val_share, self.split, self.seed + 1)

        self.scaler = StandardScaler().fit(features[self.train_idx])
        self.X = self.scaler.transform(features)
        self.y = targets
        return self

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

    def folds(self, n_folds: int | None = None):
        """K-fold (fit, held) index pairs over the training split, grouped when the split is."""
        return fold_indices(self.train_idx, self.table.groups, n_folds or self.n_folds, self.split, self.seed)

    def summary(self) -> dict:
        return {"split": self.split, "n_train": int(self.train_idx.size), "n_val": int(self.val_idx.size),
                "n_test": int(self.test_idx.size), "n_features": len(self.feature_names),
                "channels": self.channel_names, "targets": self.target_names,
                "source": self.table.description}


def from_table(path, channel_columns, target_columns, group_columns=None, **datamodule_options):
    """`data=table`: a user's CSV/Parquet recording served by the same datamodule as a scene."""
    source = TableSource(path, channel_columns, target_columns, group_columns)
    return RegressionDataModule(source, **datamodule_options)
