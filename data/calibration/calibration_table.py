"""A rig's calibration presses as the datamodule's source: `experiment=calibrate data=table`.

The same CSV/Parquet as `data=table`, one row per press, with the scene's targets as columns
(rubber12: x_mm, y_mm, depth_mm, pressure_pa; taxels: x_mm, y_mm, normal_n, shear_x_n,
shear_y_n; capacitive6x6: force_n, x_mm, y_mm) and one column per channel the scene reads,
named as the scene names them or mapped by `calibration.channel_map` ({your column: the
scene's channel}). The table is then served under the scene's channel names, so the fit, the
pretraining set and the exported model read the same columns, in the scene's order.

Refused with one line: channels that do not match the scene's (the line lists the expected
ones), fewer presses than the scene has identifiable parameters; the table itself is checked as
every user table is (data/sensor_table.py: numbers, finite, within each unit's physical range).
"""
from common.errors import InputError
from data.calibration.identifiable import calibration_for
from data.calibration.press_simulation import channel_names
from data.datamodules.regression import RegressionDataModule
from data.readers.table_reader import read_table_file
from data.sensor_table import SensorTable, TableSource

MAX_LISTED = 12   # expected channels named in full up to this many, then the first and last


def _listed(names: list[str]) -> str:
    return ", ".join(names) if len(names) <= MAX_LISTED else f"{names[0]}, {names[1]}, ... {names[-1]} ({len(names)})"


class CalibrationTableSource:
    """A user's presses checked against a scene's channels and targets."""

    def __init__(self, path: str, scene, channel_map: dict | None = None, group_columns=None,
                 split_column: str | None = "split"):
        self.path = path
        self.scene = scene
        self.channel_map = dict(channel_map or {})
        self.group_columns = group_columns
        self.split_column = split_column
        self.name = scene.name

    def load(self) -> SensorTable:
        calibration = calibration_for(self.scene)
        expected = channel_names(self.scene)
        targets = list(calibration.inputs) + list(calibration.outputs)
        unknown = sorted(set(self.channel_map.values()) - set(expected))
        if unknown:
            raise InputError(f"calibration.channel_map maps to {', '.join(unknown)}, which scene {self.scene.name} "
                             f"does not read; its channels: {_listed(expected)}")
        columns = read_table_file(self.path).columns
        column_of = {scene_name: table_name for table_name, scene_name in self.channel_map.items()}
        wanted = [column_of.get(name, name) for name in expected]
        missing = [name for name, column in zip(expected, wanted) if column not in columns]
        if missing:
            raise InputError(f"{self.path}: channels do not match scene {self.scene.name}: expected "
                             f"{_listed(expected)}; missing {_listed(missing)} (name your columns so, or map them "
                             "with calibration.channel_map={your_column: scene_channel})")
        absent = [t for t in targets if t not in columns]
        if absent:
            raise InputError(f"{self.path}: calibration presses of scene {self.scene.name} need target column(s) "
                             f"{', '.join(targets)}; missing {', '.join(absent)}")
        table = TableSource(self.path, wanted, targets, self.group_columns, self.split_column, "regression").load()
        if len(table.frame) < len(calibration.parameters):
            raise InputError(f"{self.path}: {len(table.frame)} presses; calibrating scene {self.scene.name} needs at "
                             f"least {len(calibration.parameters)} (one per identifiable parameter), more for a "
                             "validation choice (20 or more)")
        table.frame = table.frame.rename(columns=dict(zip(wanted, expected)))
        table.channel_columns = expected
        table.description.update(scene=self.scene.name, channel_map=self.channel_map)
        return table


def from_calibration_table(path, scene, channel_map=None, group_columns=None, split_column="split",
                           target_columns=None, channel_columns=None, task="auto",
                           **datamodule_options) -> RegressionDataModule:
    """The datamodule of experiment=calibrate: the user's presses under the scene's channel names
    (data=table's other settings: the targets are the scene's, channels are mapped, not chosen)."""
    expected = list(calibration_for(scene).inputs) + list(calibration_for(scene).outputs)
    if target_columns is not None and sorted(target_columns) != sorted(expected):
        raise InputError(f"experiment=calibrate learns scene {scene.name}'s targets {', '.join(expected)}; "
                         f"leave data.target_columns unset (got {', '.join(map(str, target_columns))})")
    if channel_columns is not None or task not in ("auto", "regression"):
        raise InputError("experiment=calibrate reads the scene's channels as regression; map yours with "
                         "calibration.channel_map={your_column: scene_channel} instead of data.channel_columns/task")
    return RegressionDataModule(CalibrationTableSource(path, scene, channel_map, group_columns, split_column),
                                **datamodule_options)
