"""`data=recordings_npz` and `data=recordings_table`: a user's recordings file, named by
`data.path` as every data source names its file (tables: data/datamodules/regression.py
from_table). The source reads the file through `${data.path}` (configs/data/recordings_*.yaml);
the datamodule is the one every recording set goes through (data/datamodules/timeseries.py)."""
from data.datamodules.timeseries import TimeSeriesDataModule


def from_recordings_file(path, source, **datamodule_options) -> TimeSeriesDataModule:
    """`path` is data.path, given to `source` by interpolation; it is a parameter here so that a
    data node holds its file under one key whatever the source."""
    return TimeSeriesDataModule(source, **datamodule_options)
