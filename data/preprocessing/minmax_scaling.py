"""Min-max channel normalisation that keeps its constants, so a model trained on normalised
channels can be deployed on raw readings.

The lab normalised each channel over the whole data set: r_norm = (r - minimum) / span, with
span = maximum - minimum; a channel that never changes (span 0) maps to 0. A model fitted on
r_norm needs the same minimum and span wherever it runs, so `MinMaxScaling` keeps them with the
raw channel names, and its torch module `MinMaxNormalise` is the one implementation of the map:
the scene effect normalises the data set with it (data/scenes/rubber12_effects.py), the
deployable pipeline applies it to raw readings before the features (models/deployable.py), and
the exported ONNX graph contains it (export/torch_graphs.py). Raw readings outside the data
set's range map outside [0, 1]; they are not clipped (that would hide a drifted sensor).
"""
from dataclasses import dataclass

import numpy as np
import torch
from torch import nn


class MinMaxNormalise(nn.Module):
    """(batch, channels) raw readings -> (r - minimum) / span per channel, in float64."""

    def __init__(self, minimum, span):
        super().__init__()
        span = torch.as_tensor(np.asarray(span), dtype=torch.float64)
        # float64 buffers: a Python scalar or a float32 constant would lose the readings' digits
        # (1.7e4-ohm channels with spans of a few ohms) on their way into the ONNX graph. The
        # dead-channel mask and divisor are fixed here, not in forward: computed from constants
        # in the graph, onnxruntime tries to fold them and warns on stderr at every load.
        self.register_buffer("minimum", torch.as_tensor(np.asarray(minimum), dtype=torch.float64))
        self.register_buffer("live", span > 0)
        self.register_buffer("divisor", torch.where(span > 0, span, torch.ones_like(span)))  # no 0/0

    def forward(self, readings: torch.Tensor) -> torch.Tensor:
        r = readings.double()
        return torch.where(self.live, (r - self.minimum) / self.divisor, torch.zeros_like(r))


@dataclass
class MinMaxScaling:
    raw_channels: list[str]  # the readings it takes, units in the names (r_01_ohm, ...)
    minimum: np.ndarray      # per channel, in the raw unit
    span: np.ndarray         # per channel maximum - minimum, in the raw unit; 0 = never changed

    @classmethod
    def fit(cls, readings, raw_channels) -> "MinMaxScaling":
        r = np.asarray(readings, dtype=np.float64)
        return cls(list(raw_channels), r.min(axis=0), np.ptp(r, axis=0))

    def module(self) -> MinMaxNormalise:
        return MinMaxNormalise(self.minimum, self.span)

    def normalise(self, readings) -> np.ndarray:
        """(n, channels) raw readings -> normalised, float64."""
        r = np.ascontiguousarray(readings, dtype=np.float64)
        with torch.no_grad():
            return self.module()(torch.from_numpy(r)).numpy()

    def raw(self, normalised) -> np.ndarray:
        """The raw readings that normalise to `normalised` (to rounding; a dead channel reads its minimum)."""
        return self.minimum + np.asarray(normalised, dtype=np.float64) * self.span
