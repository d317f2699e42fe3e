"""Sets of time-series recordings: what the fingertip scene simulates and a rig records.

One recording per pass: `signals` of shape (n_recordings, n_channels, n_timesteps), channel
names with units, a label table (one row per recording) and the sample rate (None when the data
do not say). The label table may carry a `split` column (train / val / test per recording): the
side a data set declares, used unless data.declared_split=ignore (data/splits/indices.py).

Whoever builds a RecordingSet (a scene, a user's NPZ or table), it is checked on construction:
at least one recording, channel and step; every signal value finite in float32 (the dtype the
signals are kept in, the one the networks compute in) and within the physical range of the unit
its channel's name carries (data/units.py); numeric label columns with a unit likewise
(force_level_n >= 0).
"""
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from common.errors import InputError
from data.readers.table_reader import MODEL_DTYPE, MODEL_DTYPE_MAX
from data.units import first_outside


@dataclass
class RecordingSet:
    signals: np.ndarray
    channel_names: list[str]
    labels: pd.DataFrame
    sample_rate_hz: float | None
    description: dict = field(default_factory=dict)

    def __post_init__(self):
        source = self.description.get("path") or (f"scene {self.description['scene']}"
                                                  if "scene" in self.description else "the recordings")
        check_signals(self.signals, self.channel_names, source)
        self.signals = np.asarray(self.signals, dtype=MODEL_DTYPE)
        if len(self.labels) != len(self.signals):
            raise InputError(f"{source}: {len(self.labels)} label rows for {len(self.signals)} recordings")
        for column in self.labels.columns:
            values = self.labels[column]
            if values.dtype.kind in "iuf":
                outside = first_outside(values.to_numpy(), str(column))
                if outside is not None:
                    k, value, rule = outside
                    raise InputError(f"{source}: label '{column}' of recording {k} is {value:g}; {rule.describe()}")

    def __len__(self) -> int:
        return len(self.signals)

    @property
    def time_s(self) -> np.ndarray:
        if self.sample_rate_hz is None:
            raise ValueError("these recordings declare no sample rate, so they have no time axis")
        return np.arange(self.signals.shape[-1]) / self.sample_rate_hz

    def channel(self, name: str) -> np.ndarray:
        """(n_recordings, n_timesteps) view of one channel by name."""
        return self.signals[:, self.channel_names.index(name)]

    def select(self, mask) -> "RecordingSet":
        mask = np.asarray(mask)
        return RecordingSet(self.signals[mask], list(self.channel_names),
                            self.labels[mask].reset_index(drop=True), self.sample_rate_hz, dict(self.description))


def check_signals(signals: np.ndarray, channel_names: list[str], source: str) -> None:
    """(n, channels, steps) numeric, none of the sizes zero, one name per channel, every value
    finite in float32 and physical for its channel's unit; one line naming the first culprit."""
    signals = np.asarray(signals)
    if signals.ndim != 3:
        raise InputError(f"{source}: recordings must be (n, channels, length), got shape {signals.shape}")
    if signals.dtype.kind not in "iuf":
        raise InputError(f"{source}: signals must be real numbers, got dtype {signals.dtype}")
    for size, what in zip(signals.shape, ("recordings", "channels", "time steps")):
        if size == 0:
            raise InputError(f"{source}: no {what} (signals of shape {signals.shape})")
    if len(channel_names) != signals.shape[1]:
        raise InputError(f"{source}: {len(channel_names)} channel names for {signals.shape[1]} channels")
    for c, name in enumerate(channel_names):
        channel = signals[:, c]
        with np.errstate(over="ignore"):
            bad = ~np.isfinite(channel.astype(MODEL_DTYPE))
        if bad.any():
            k, t = np.unravel_index(int(np.flatnonzero(bad)[0]), channel.shape)
            value = float(channel[k, t])
            problem = (f"{value:g}, beyond the largest float32 ({MODEL_DTYPE_MAX:.4g}): the models compute in "
                       "float32, where it is infinite") if np.isfinite(value) else f"{value} (missing or infinite)"
            raise InputError(f"{source}: channel '{name}' of recording {k} at step {t} is {problem}")
        outside = first_outside(channel, str(name))
        if outside is not None:
            flat, value, rule = outside
            k, t = np.unravel_index(flat, channel.shape)
            raise InputError(f"{source}: channel '{name}' of recording {k} at step {t} is {value:g}; {rule.describe()}")
