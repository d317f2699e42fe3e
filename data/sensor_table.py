"""Tables of presses: what a scene simulates and what a user's rig recorded look the same.

A SensorTable holds one row per press: channel columns (inputs), target columns (what to
learn, units in their names) and a group id per row (all repeats of one position-depth
pair share a group, so grouped splits can keep them on one side). An optional `split` gives
each row the side its source declares (train / val / test), the split the datamodule uses unless
data.declared_split=ignore: a user's file with a split column, or a scene that models a published
protocol. When the channels were
normalised from raw readings (scene rubber12_lab's min-max step), `normalisation` keeps how,
so a model trained on them can be deployed on the raw readings.

Whoever builds a SensorTable (a scene, a user's file), its channels and targets are checked on
construction (data/readers/table_reader.py: check_model_values): finite, finite in float32, and within the
physical range of the unit each name carries; at least one channel and one target.
"""
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from common.errors import InputError
from data.preprocessing.minmax_scaling import MinMaxScaling
from data.readers.table_reader import check_columns_exist, check_model_values, numeric_column, read_table_file, where
from data.splits.indices import split_values


@dataclass
class SensorTable:
    frame: pd.DataFrame
    channel_columns: list[str]
    target_columns: list[str]
    groups: np.ndarray
    description: dict = field(default_factory=dict)
    normalisation: MinMaxScaling | None = None  # raw readings -> channel_columns; None: channels are raw
    split: np.ndarray | None = None  # one of train / val / test per row, or None: the source declares none

    def __post_init__(self):
        if self.split is not None and len(self.split) != len(self.frame):
            raise InputError(f"a split label per row is needed: {len(self.split)} labels for {len(self.frame)} rows")
        source = self.source_name
        for what, columns in (("channel", self.channel_columns), ("target", self.target_columns)):
            if not columns:
                raise InputError(f"{source}: no {what} columns (data.{what}_columns is empty)")
            check_columns_exist(self.frame, columns, what, source)
            for column in columns:
                check_model_values(self.frame[column].to_numpy(dtype=np.float64), column, what, source)

    @property
    def source_name(self) -> str:
        """How error messages name this table: its file, else its scene."""
        if "path" in self.description:
            return str(self.description["path"])
        return f"scene {self.description['scene']}" if "scene" in self.description else "the table"

    @property
    def channels(self) -> np.ndarray:
        return self.frame[self.channel_columns].to_numpy(dtype=np.float64)

    @property
    def targets(self) -> np.ndarray:
        return self.frame[self.target_columns].to_numpy(dtype=np.float64)


class TableSource:
    """A user's recording: `data=table data.path=rig.csv`, columns named in the config.
    A `split_column` present in the file is kept as the rows' declared split (the datamodule's
    split unless data.declared_split=ignore); absent, the table declares none."""

    def __init__(self, path: str, channel_columns: list[str], target_columns: list[str],
                 group_columns: list[str] | None = None, split_column: str | None = "split"):
        self.path = path
        self.channel_columns = list(channel_columns)
        self.target_columns = list(target_columns)
        self.group_columns = list(group_columns) if group_columns else None
        self.split_column = split_column

    def load(self) -> SensorTable:
        frame = read_table_file(self.path)
        both = sorted(set(self.channel_columns) & set(self.target_columns))
        if both:
            raise InputError(f"{self.path}: column(s) {', '.join(both)} listed as both channel and target "
                             "(a model would be given the answer)")
        numeric = {}
        for what, columns in (("channel", self.channel_columns), ("target", self.target_columns)):
            check_columns_exist(frame, columns, what, self.path)
            numeric.update({c: numeric_column(frame[c], c, what, self.path) for c in columns})
        numeric = pd.DataFrame(numeric, columns=self.channel_columns + self.target_columns)
        if self.group_columns:
            missing = [c for c in self.group_columns if c not in frame.columns]
            if missing:
                raise InputError(f"{self.path}: missing group column(s) {', '.join(missing)}")
            # a group column that is a channel or target is grouped by its checked float64 values
            # (pandas cannot group float16); another must hold hashable values (not lists)
            keys = pd.DataFrame({c: numeric[c] if c in numeric else frame[c] for c in self.group_columns})
            try:
                groups = keys.groupby(self.group_columns, sort=True, dropna=False).ngroup().to_numpy()
            except (TypeError, NotImplementedError) as error:
                raise InputError(f"{self.path}: group column(s) {', '.join(self.group_columns)} cannot be grouped "
                                 f"({str(error).splitlines()[0]})") from None
        else:
            groups = np.arange(len(frame))
        split = None
        if self.split_column and self.split_column in frame.columns:
            split = split_values(frame[self.split_column].to_numpy(), f"{self.path}: column '{self.split_column}'",
                                 lambda row: where(self.path, row))
        return SensorTable(numeric, self.channel_columns, self.target_columns, groups,
                           {"source": "table", "path": str(self.path)}, split=split)
