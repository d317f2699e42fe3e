"""The seed paper's "physics-inspired" feature operators on raw channel readings.

Groups, in this order (c = number of channels; 12 for rubber12):
  raw            r_i                                  c
  log1p          log(1 + |r_i|)                       c
  sqrt           sqrt(|r_i|)                          c
  zscore         (r_i - mean) / (std + 1e-8)          c   (per sample, across channels)
  stats          mean, std, skew, kurtosis            4   (per sample, across channels)
  pair_products  r_i * r_{i+1}                        c-1 (neighbouring channels, i = 1..c-1)
  pair_ratios    r_i / (|r_{i+1}| + eps)              c-1 (eps: see below)
For 12 channels with every group on that is 4*12 + 4 + 2*11 = 74 features. (The paper says 49
but its own list does not add up to 49; this is the list it describes.)

std is the population standard deviation; skew and kurtosis are the standardised third
moment and the *excess* fourth moment, in closed form (scipy.stats is ~50x slower per
sample). For a sample whose channels are all equal (to float64 rounding: std <= 1e-12 |mean|)
they are undefined; we define both as 0, as are the z-scores and the std (rounding noise). Everything is computed in float64 and is finite for every finite
non-negative input.

Ratios: a fixed epsilon (1e-8) is no guard when channels are min-max normalised, since every
channel is exactly 0 at its minimum and 1 / 1e-8 = 1e8 then swamps the scaler. The guard
scales with the sample instead: eps = 1e-4 * sum_j |r_j|, the sample's total reading, floored
at 1e-300 so an all-zero sample gives 0 / 1e-300 = 0. Hence |ratio| <= |r_i| / eps <= 1e4 for
every finite sample, whatever the unit and the channel count; for 12 channels of similar size
eps is 0.12 % of the mean reading, so ordinary ratios move by about 0.1 %. The denominator uses
|r_{i+1}| so a slightly negative reading (raw ohms below the training minimum, once normalised)
cannot cancel eps and divide by zero; for non-negative readings it is r_{i+1} itself.

One implementation: the operators are a torch module (`PhysicsFeatures`), called on numpy
arrays in training (`compute_features`) and on tensors inside the exported ONNX graph.
"""
from functools import lru_cache

import numpy as np
import torch
from torch import nn

from common.errors import InputError

FEATURE_GROUPS = ("raw", "log1p", "sqrt", "zscore", "stats", "pair_products", "pair_ratios")
EPSILON = 1e-8               # z-scores: (r - mean) / (std + EPSILON)
RATIO_EPSILON = 1e-4         # pair ratios: eps = RATIO_EPSILON * sum_j |r_j|, so |ratio| <= 1 / RATIO_EPSILON


def enabled_groups(groups) -> list[str]:
    """Accepts a mapping group -> bool (the config) or a list of names; keeps the canonical order."""
    chosen = [g for g, on in groups.items() if on] if hasattr(groups, "items") else list(groups)
    unknown = sorted(set(chosen) - set(FEATURE_GROUPS))
    if unknown:
        raise InputError(f"unknown feature group(s) {', '.join(unknown)}; valid: {', '.join(FEATURE_GROUPS)}")
    chosen = [g for g in FEATURE_GROUPS if g in chosen]
    if not chosen:
        raise InputError("no feature group is enabled; enable at least one of " + ", ".join(FEATURE_GROUPS))
    return chosen


def feature_names(channels: list[str], groups) -> list[str]:
    names = []
    pairs = list(zip(channels[:-1], channels[1:]))
    for group in enabled_groups(groups):
        if group in ("raw", "log1p", "sqrt", "zscore"):
            names += [f"{group}:{c}" for c in channels]
        elif group == "stats":
            names += ["stats:mean", "stats:std", "stats:skew", "stats:kurtosis"]
        elif group == "pair_products":
            names += [f"product:{a}*{b}" for a, b in pairs]
        else:
            names += [f"ratio:{a}/{b}" for a, b in pairs]
    return names


class PhysicsFeatures(nn.Module):
    """(batch, channels) readings -> (batch, features), computed in float64 (so a constant
    sample's shape statistics are exactly 0, and products of 1e9-ohm readings stay exact)."""

    def __init__(self, groups):
        super().__init__()
        self.groups = enabled_groups(groups)
        # Small constants as float64 buffers keep their exact values (a Python scalar passes
        # through float32 in the ONNX exporter: 1e-12 became 9.99999996e-13).
        self.register_buffer("epsilon", torch.tensor(EPSILON, dtype=torch.float64))
        self.register_buffer("ratio_epsilon", torch.tensor(RATIO_EPSILON, dtype=torch.float64))
        self.register_buffer("relative_floor", torch.tensor(1e-12, dtype=torch.float64))
        self.register_buffer("tiny", torch.tensor(1e-300, dtype=torch.float64))  # absolute floor of a scale

    def forward(self, r: torch.Tensor) -> torch.Tensor:
        r = r.double()
        mean = r.mean(dim=1, keepdim=True)
        centred = r - mean
        std = torch.sqrt((centred * centred).mean(dim=1, keepdim=True))
        # Standardise only where the spread is resolvable in float64; elsewhere the sample is
        # constant to rounding (twelve equal 1.2e11-ohm readings average to a mean 1 ulp off,
        # and (r - mean) / (std + 1e-8) would be +/-1) and z-scores and shape statistics are 0.
        resolvable = std > self.relative_floor * torch.maximum(mean.abs(), self.tiny)
        zero = torch.zeros_like(centred)
        z = torch.where(resolvable, centred / torch.where(resolvable, std, torch.ones_like(std)), zero)
        blocks = []
        for group in self.groups:
            if group == "raw":
                blocks.append(r)
            elif group == "log1p":
                blocks.append(torch.log1p(r.abs()))
            elif group == "sqrt":
                blocks.append(torch.sqrt(r.abs()))
            elif group == "zscore":
                blocks.append(torch.where(resolvable, centred / (std + self.epsilon), zero))
            elif group == "stats":
                skew = (z ** 3).mean(dim=1, keepdim=True)
                kurtosis = torch.where(resolvable, (z ** 4).mean(dim=1, keepdim=True) - 3.0, torch.zeros_like(mean))
                blocks.append(torch.cat([mean, torch.where(resolvable, std, torch.zeros_like(std)), skew, kurtosis], dim=1))
            elif group == "pair_products":
                blocks.append(r[:, :-1] * r[:, 1:])
            else:
                guard = torch.maximum(self.ratio_epsilon * r.abs().sum(dim=1, keepdim=True), self.tiny)
                blocks.append(r[:, :-1] / (r[:, 1:].abs() + guard))
        return torch.cat(blocks, dim=1)


def compute_features(readings, groups) -> np.ndarray:
    """(n_samples, n_channels) readings -> (n_samples, n_features) float64, groups in canonical order."""
    r = np.asarray(readings, dtype=np.float64)
    if r.ndim != 2 or r.shape[1] < 2:
        raise InputError(f"features need a 2-D array with at least 2 channels, got shape {r.shape}")
    with torch.no_grad():
        return _module(tuple(enabled_groups(groups)))(torch.from_numpy(np.ascontiguousarray(r))).numpy()


@lru_cache(maxsize=16)
def _module(groups: tuple[str, ...]) -> PhysicsFeatures:
    """One module per choice of groups: building it costs more than running it on one sample."""
    return PhysicsFeatures(groups)
