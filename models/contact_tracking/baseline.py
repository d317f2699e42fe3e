"""Baseline and noise model (the paper's sec. 2.4.3, eqs. 4-6): each cell's rest mean and spread
from contact-free frames, and the threshold a reading must pass to count as touched.

`threshold="variance"` is eq. (6) as printed and as the public code (capsensor-monitor,
src/processor.py) computes it: mean + c * sigma^2, kept with `>=` as that code keeps it. A
variance has squared units, so its meaning changes with the board's gain; `"std"` (the default)
uses mean + c * sigma, a spread in the reading's own units (c = 5 keeps Gaussian noise above
threshold about 3 times in 10 million cells), sigma floored at `min_spread` so that a cell that
never moved at rest (e.g. saturated) cannot fire on one count.
"""
from dataclasses import dataclass

import numpy as np

from common.errors import InputError

THRESHOLDS = ("std", "variance")


@dataclass(eq=False)
class Baseline:
    mean: np.ndarray            # per cell, counts
    variance: np.ndarray
    spread: np.ndarray          # sigma, floored
    kind: str                   # "std" | "variance"
    sensitivity: float          # c of eq. (6)
    hold_sensitivity: float     # c next to a live contact (hysteresis), at most `sensitivity`
    threshold: np.ndarray = None
    hold_threshold: np.ndarray = None

    def __post_init__(self):
        self.set_thresholds()

    def set_thresholds(self):
        term = self.variance if self.kind == "variance" else self.spread
        self.threshold = self.mean + self.sensitivity * term
        self.hold_threshold = self.mean + self.hold_sensitivity * term


def fit_baseline(frames: np.ndarray, discard_frames: int, min_rest_frames: int, kind: str, sensitivity: float,
                 hold_sensitivity: float | None, min_spread: float) -> Baseline:
    """Rest mean and spread per cell (eqs. 4-5, 1/N as the paper) from (frames, cells) rest frames,
    after dropping the first `discard_frames` (the paper drops 5 "unstable" samples)."""
    if not np.isfinite(frames).all():
        raise InputError("rest frames: NaN or infinite cell value")
    usable = frames[int(discard_frames):]
    if len(usable) < min_rest_frames:
        raise InputError(f"rest frames: {len(frames)} given, {len(usable)} left after discarding "
                         f"{discard_frames}; a baseline needs at least {min_rest_frames}")
    variance = usable.var(axis=0)
    hold = sensitivity if hold_sensitivity is None else min(hold_sensitivity, sensitivity)
    return Baseline(usable.mean(axis=0), variance, np.maximum(np.sqrt(variance), float(min_spread)), kind,
                    sensitivity, hold)


def above_threshold(baseline: Baseline, x: np.ndarray, near_contact: np.ndarray | None) -> np.ndarray:
    """Cells that count as touched: above the threshold (the public code zeroes `x < threshold`,
    i.e. keeps `>=`, in "variance" mode), or above the lower hold threshold next to last frame's
    contacts (hysteresis thresholding, Canny 1986: a contact once found is followed further down)."""
    above = x >= baseline.threshold if baseline.kind == "variance" else x > baseline.threshold
    if near_contact is not None:
        above |= near_contact & (x > baseline.hold_threshold)
    return above


def follow_drift(baseline: Baseline, x: np.ndarray, above: np.ndarray, rate: float) -> None:
    """Move the rest mean of each cell below threshold towards its reading by `rate` (an
    exponential average); touched cells keep their mean."""
    baseline.mean += rate * (x - baseline.mean) * ~above
    baseline.set_thresholds()
