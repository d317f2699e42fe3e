"""Sets of time-series recordings: what the fingertip scene simulates and a rig records.

One recording per pass: `signals` of shape (n_recordings, n_channels, n_timesteps), channel
names with units, a label table (one row per recording) and the sample rate (None when the data
do not say). The label table may carry a `split` column (train / val / test per recording): the
side a data set declares, used by `data.split=predefined`.
"""
from dataclasses import dataclass, field

import numpy as np
import pandas as pd


@dataclass
class RecordingSet:
    signals: np.ndarray
    channel_names: list[str]
    labels: pd.DataFrame
    sample_rate_hz: float | None
    description: dict = field(default_factory=dict)

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
