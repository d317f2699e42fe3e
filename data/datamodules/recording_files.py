"""`data=recordings_npz` and `data=recordings_table`: a user's recordings file, named by
`data.path` as every data source names its file (tables: data/datamodules/regression.py
from_table). The source node is a partial (configs/data/recordings_*.yaml) completed here with
the path; the datamodule is the one every recording set goes through (data/datamodules/timeseries.py)."""
from data.datamodules.timeseries import TimeSeriesDataModule


def from_recordings_file(path, source, **datamodule_options) -> TimeSeriesDataModule:
    """`source`: a reader class's partial (NpzRecordings, LongTableRecordings) still to be told `path`."""
    return TimeSeriesDataModule(source(path=path), **datamodule_options)
