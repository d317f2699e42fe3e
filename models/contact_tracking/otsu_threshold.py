"""Otsu's threshold on the few values of one frame, exactly (no histogram).

Used by the contact tracker's detection (detection.py) to cut each frame's grey image; kept
apart because it is a general image-thresholding step, tested on its own against scikit-image.
"""
import functools

import numpy as np


def otsu_threshold(values: np.ndarray) -> float:
    """Otsu's threshold (Otsu 1979, eq. 18: maximise the between-class variance
    sigma_B^2 = (mu_T omega(k) - mu(k))^2 / (omega(k) (1 - omega(k)))) over the sorted values
    themselves rather than a 256-bin histogram: exact for the few cells of a frame. Returns t
    such that `values >= t` is the upper class; with a single distinct value everything is."""
    v = np.sort(values)
    n = v.size
    low, high = v[0], v[-1]  # numpy scalars: cheaper than a fancy index and a list
    if low == high:
        return float(low)
    k, k_times_rest = _split_counts(n)
    below = np.add.accumulate(v[:-1])  # the ufunc method: no array-method wrapper (~1 us a call here)
    # n^2 sigma_B^2 up to a constant factor: (S(k) - k S(n)/n)^2 / (k (n - k)); in place, fewest calls
    between = k * ((below[-1] + high) / n)
    np.subtract(below, between, out=between)
    between *= between
    between /= k_times_rest
    between *= v[1:] > v[:-1]  # a split must fall between two distinct values (between >= 0; the best is > 0)
    return float(v[int(between.argmax()) + 1])


@functools.lru_cache(maxsize=512)
def _split_counts(n: int) -> tuple[np.ndarray, np.ndarray]:
    """k = 1..n-1 and k (n - k): the class sizes of every split of n sorted values."""
    k = np.arange(1.0, n)
    return k, k * (n - k)
