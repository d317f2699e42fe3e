"""Tables of presses: what a scene simulates and what a user's rig recorded look the same.

A SensorTable holds one row per press: channel columns (inputs), target columns (what to
learn, units in their names) and a group id per row (all repeats of one position-depth
pair share a group, so grouped splits can keep them on one side). When the channels were
normalised from raw readings (scene rubber12_lab's min-max step), `normalisation` keeps how,
so a model trained on them can be deployed on the raw readings.
"""
from dataclasses import dataclass, field
import numpy as np
import pandas as pd

from data.errors import InputError
from data.minmax_scaling import MinMaxScaling
from data.table_files import check_numeric_columns, read_table_file


@dataclass
class SensorTable:
    frame: pd.DataFrame
    channel_columns: list[str]
    target_columns: list[str]
    groups: np.ndarray
    description: dict = field(default_factory=dict)
    normalisation: MinMaxScaling | None = None  # raw readings -> channel_columns; None: channels are raw

    @property
    def channels(self) -> np.ndarray:
        return self.frame[self.channel_columns].to_numpy(dtype=np.float64)

    @property
    def targets(self) -> np.ndarray:
        return self.frame[self.target_columns].to_numpy(dtype=np.float64)


class TableSource:
    """A user's recording: `data=table data.source.path=rig.csv`, columns named in the config."""

    def __init__(self, path: str, channel_columns: list[str], target_columns: list[str],
                 group_columns: list[str] | None = None):
        self.path = path
        self.channel_columns = list(channel_columns)
        self.target_columns = list(target_columns)
        self.group_columns = list(group_columns) if group_columns else None

    def load(self) -> SensorTable:
        frame = read_table_file(self.path)
        check_numeric_columns(frame, self.channel_columns, "channel", self.path)
        check_numeric_columns(frame, self.target_columns, "target", self.path)
        columns = self.channel_columns + self.target_columns
        numeric = frame[columns].apply(pd.to_numeric).astype(np.float64)
        if self.group_columns:
            missing = [c for c in self.group_columns if c not in frame.columns]
            if missing:
                raise InputError(f"{self.path}: missing group column(s) {', '.join(missing)}")
            groups = frame.groupby(self.group_columns, sort=True, dropna=False).ngroup().to_numpy()
        else:
            groups = np.arange(len(frame))
        return SensorTable(numeric, self.channel_columns, self.target_columns, groups,
                           {"source": "table", "path": str(self.path)})
