"""Cut recordings into fixed-length windows, as the seed paper does.

Each recording (channels x steps) is optionally decimated (block means of `decimate` steps:
a boxcar low-pass, so 50 Hz hum does not alias in), trimmed at both ends (the idle
"redundant" points before the approach and after the separation), and cut into windows of
`length` steps every `step` steps. Windows whose variance on `variance_channel` is below
`min_variance` are dropped (flat stretches carry no texture). Paper: no decimation,
length 1400 at 250 Hz, step 10. A `length` of None takes each (trimmed) recording whole, as
one window: what a data set of fixed-length series (one label per series) is classified by.
A `step` of None puts windows back to back (step = length).
"""
import numpy as np

from common.errors import InputError


def decimate(signals, factor: int):
    """Block means over the last axis; a trailing partial block is dropped. The same code runs
    on numpy arrays (training) and torch tensors (the exported graph)."""
    if factor < 1:
        raise InputError(f"data.decimate must be >= 1, got {factor}")
    if factor == 1:
        return signals
    usable = signals.shape[-1] // factor * factor
    blocks = signals[..., :usable]
    return blocks.reshape(tuple(blocks.shape[:-1]) + (usable // factor, factor)).mean(-1)


def window_starts(n_steps: int, length: int, step: int) -> np.ndarray:
    if length < 1 or step < 1:
        raise InputError(f"window length and step must be >= 1, got {length} and {step}")
    if n_steps < length:
        return np.zeros(0, dtype=np.int64)
    return np.arange(0, n_steps - length + 1, step)


def cut_windows(signals: np.ndarray, length: int | None, step: int | None, trim_start: int = 0, trim_end: int = 0,
                min_variance: float = 0.0, variance_channel: int = 0):
    """(n_recordings, channels, steps) -> windows (n_windows, channels, length) and, per window,
    the index of its recording. Raises a one-line error when no window survives."""
    signals = np.asarray(signals)
    if signals.ndim != 3:
        raise InputError(f"recordings must be (n_recordings, channels, steps), got shape {signals.shape}")
    for name, value in (("trim_start", trim_start), ("trim_end", trim_end)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
            raise InputError(f"data.{name} must be a whole number of steps >= 0, got {value!r}")
    end = signals.shape[-1] - trim_end
    trimmed = signals[..., trim_start:end]
    if trimmed.shape[-1] < 1:
        raise InputError(f"recordings of {signals.shape[-1]} steps leave no step after trimming "
                         f"{trim_start} + {trim_end}")
    length = trimmed.shape[-1] if length is None else length
    step = length if step is None else step
    starts = window_starts(trimmed.shape[-1], length, step)
    if starts.size == 0:
        raise InputError(f"recordings of {trimmed.shape[-1]} steps after trimming are shorter than the "
                         f"window length {length}")
    index = starts[:, None] + np.arange(length)[None, :]
    windows = trimmed[:, :, index]                     # (rec, ch, n_starts, length)
    windows = windows.transpose(0, 2, 1, 3).reshape(-1, signals.shape[1], length)
    recording = np.repeat(np.arange(len(signals)), starts.size)
    if min_variance > 0:
        keep = windows[:, variance_channel].var(axis=1) >= min_variance
        windows, recording = windows[keep], recording[keep]
    if len(windows) == 0:
        raise InputError(f"no window has variance >= {min_variance} on channel {variance_channel}")
    return np.ascontiguousarray(windows), recording
