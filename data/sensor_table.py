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
construction (data/readers/table_reader.py: check_model_block): finite, finite in float32, and within the
physical range of the unit each name carries; at least one channel and one target.

A table whose one target is a class label (a classification table) holds the label's class
codes 0..k-1 in its target column and the class names in `classes`.

A user's file needs only its path and its target column(s) (TableSource):
- the channels default to every numeric column that is not a target, a group or the split column;
- the task follows the target's type (data.task=auto): text, booleans or categories are class
  labels (classification); a column of whole numbers is a class label too when its name carries
  no unit (data/units.py) and it holds at most MAX_AUTO_CLASSES distinct values (a grasp id, a
  finger count), else a quantity; every other number is a quantity (regression).
  data.task=classification or regression overrides the guess;
- a missing column's error names the setting that fixes it.
"""
import logging
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from common.errors import InputError
from data.preprocessing.minmax_scaling import MinMaxScaling
from data.readers.table_reader import check_columns_exist, check_model_block, numeric_column, read_table_file, where
from data.splits.indices import split_values
from data.units import UNITS, unit_of

log = logging.getLogger(__name__)
TASKS = ("auto", "classification", "regression")
MAX_AUTO_CLASSES = 20   # task=auto: an integer column without a unit and this many values or fewer is a class label


@dataclass
class SensorTable:
    frame: pd.DataFrame
    channel_columns: list[str]
    target_columns: list[str]
    groups: np.ndarray
    description: dict = field(default_factory=dict)
    normalisation: MinMaxScaling | None = None  # raw readings -> channel_columns; None: channels are raw
    split: np.ndarray | None = None  # one of train / val / test per row, or None: the source declares none
    classes: list[str] | None = None  # a classification table: the class names its target's codes 0..k-1 stand for

    def __post_init__(self):
        if self.split is not None and len(self.split) != len(self.frame):
            raise InputError(f"a split label per row is needed: {len(self.split)} labels for {len(self.frame)} rows")
        source = self.source_name
        for what, columns in (("channel", self.channel_columns), ("target", self.target_columns)):
            if not columns:
                raise InputError(f"{source}: no {what} columns (data.{what}_columns is empty)")
            check_columns_exist(self.frame, columns, what, source)
            check_model_block(self.frame, columns, what, source)

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
    """A user's file: `data=table data.path=rig.csv data.target_columns=[...]`. Channels default
    to every numeric column that is not a target, a group or the split column. A `split_column`
    present in the file is kept as the rows' declared split (the datamodule's split unless
    data.declared_split=ignore); absent, the table declares none."""

    def __init__(self, path: str, channel_columns: list[str] | None = None, target_columns: list[str] | None = None,
                 group_columns: list[str] | None = None, split_column: str | None = "split", task: str = "auto"):
        self.path = path
        self.target_columns = list(target_columns or [])
        self.channel_columns = None if channel_columns is None else list(channel_columns)
        self.group_columns = list(group_columns) if group_columns else None
        self.split_column = split_column
        self.task = task

    def load(self) -> SensorTable:
        if self.task not in TASKS:
            raise InputError(f"data.task must be one of {', '.join(TASKS)}, got {self.task!r}")
        if not self.target_columns:
            raise InputError(f"{self.path}: no target columns; set data.target_columns=[...]")
        frame = read_table_file(self.path)
        for what, columns in (("target", self.target_columns), ("group", self.group_columns or []),
                              ("channel", self.channel_columns or [])):
            check_columns_exist(frame, columns, what, self.path, setting=f"data.{what}_columns")
        channels = self.channel_columns if self.channel_columns is not None else self._default_channels(frame)
        both = sorted(set(channels) & set(self.target_columns))
        if both:
            raise InputError(f"{self.path}: column(s) {', '.join(both)} listed as both channel and target "
                             "(a model would be given the answer)")
        task = self.task if self.task != "auto" else inferred_task(frame, self.target_columns)
        numeric = {c: numeric_column(frame[c], c, "channel", self.path) for c in channels}
        classes = None
        if task == "classification":
            (target,) = self._single_target()
            codes, classes = class_codes(frame[target], target, self.path)
            numeric[target] = codes
        else:
            numeric.update({c: numeric_column(frame[c], c, "target", self.path, hint=CLASS_HINT)
                            for c in self.target_columns})
        numeric = pd.DataFrame(numeric, columns=channels + self.target_columns)
        split = None
        if self.split_column and self.split_column in frame.columns:
            split = split_values(frame[self.split_column].to_numpy(), f"{self.path}: column '{self.split_column}'",
                                 lambda row: where(self.path, row))
        return SensorTable(numeric, channels, self.target_columns, self._groups(frame, numeric),
                           {"source": "table", "path": str(self.path), "task": task}, split=split, classes=classes)

    def _default_channels(self, frame: pd.DataFrame) -> list[str]:
        """Every numeric column (not booleans) that is not a target, a group or the split column."""
        taken = set(self.target_columns) | set(self.group_columns or []) | {self.split_column}
        channels = [c for c in frame.columns if c not in taken and frame[c].dtype.kind in "iuf"]
        if not channels:
            raise InputError(f"{self.path}: no numeric column besides the target, group and split columns to "
                             "read as channels; set data.channel_columns=[...]")
        log.info("channels: %d numeric column(s) of %s besides the target, group and split columns (%s)",
                 len(channels), self.path, ", ".join(map(str, channels)))
        return [str(c) for c in channels]

    def _single_target(self) -> list[str]:
        if len(self.target_columns) != 1:
            raise InputError(f"{self.path}: classification takes one target column (the class label), got "
                             f"{len(self.target_columns)}: {', '.join(self.target_columns)}; set "
                             "data.target_columns=[<label>]")
        return self.target_columns

    def _groups(self, frame: pd.DataFrame, numeric: pd.DataFrame) -> np.ndarray:
        """One group id per row: the distinct values of the group columns, or one row each."""
        if not self.group_columns:
            return np.arange(len(frame))
        # a group column that is a channel or target is grouped by its checked values (pandas
        # cannot group float16); another must hold hashable values (not lists)
        keys = pd.DataFrame({c: numeric[c] if c in numeric else frame[c] for c in self.group_columns})
        try:
            return keys.groupby(self.group_columns, sort=True, dropna=False).ngroup().to_numpy()
        except (TypeError, NotImplementedError) as error:
            raise InputError(f"{self.path}: group column(s) {', '.join(self.group_columns)} cannot be grouped "
                             f"({str(error).splitlines()[0]})") from None


CLASS_HINT = "; for class labels set data.task=classification"


def inferred_task(frame: pd.DataFrame, target_columns: list[str]) -> str:
    """data.task=auto: classification when the one target is a class label by its type (the module
    docstring's rule), else regression."""
    if len(target_columns) != 1:
        return "regression"
    column = frame[target_columns[0]]
    kind = column.dtype.kind
    if kind in "OSUb" or isinstance(column.dtype, pd.CategoricalDtype):
        return "classification"
    if kind in "iu" and unit_of(target_columns[0]) not in UNITS and column.nunique() <= MAX_AUTO_CLASSES:
        return "classification"
    return "regression"


def class_codes(column: pd.Series, name: str, source) -> tuple[np.ndarray, list[str]]:
    """(codes 0..k-1 as float64, class names) of a label column: names are the values as text,
    sorted (numbers numerically); a missing label is a one-line error naming its row."""
    missing = column.isna().to_numpy()
    if missing.any():
        raise InputError(f"{source}: target column '{name}' has a missing class label in "
                         f"{where(source, int(np.flatnonzero(missing)[0]))}")
    labels = column.to_numpy() if column.dtype.kind in "iufb" else column.astype(str).to_numpy()
    values = np.unique(labels)
    codes = np.searchsorted(values, labels)
    return codes.astype(np.float64), [str(v) for v in values]
