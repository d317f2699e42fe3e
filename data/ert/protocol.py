"""Injection and measurement patterns of an ERT frame and the names of its channels (seed 002
§3.4, eq. 2): current `current_a` into a and out of b for each injection pair, the voltage read
between c and d for each measurement pair, channels injection-major."""
from itertools import combinations

import numpy as np

from common.errors import InputError


def injection_pairs(injection, n_electrodes: int) -> np.ndarray:
    """0-based injection pairs: `all` = every unordered pair (N(N-1)/2), `adjacent` = each
    electrode with the next in numbering, or a list of 1-based [a, b] pairs."""
    if injection == "all":
        return np.array(list(combinations(range(n_electrodes), 2)), dtype=np.int64)
    if injection == "adjacent":
        first = np.arange(n_electrodes)
        return np.column_stack([first, (first + 1) % n_electrodes])
    return _explicit_pairs(injection, n_electrodes, "injection")


def measurement_pairs(measurement, n_electrodes: int) -> np.ndarray:
    """0-based measurement pairs: `successive` = (c, c+1) cyclically (seed 002 §4.3), or a list."""
    if measurement == "successive":
        first = np.arange(n_electrodes)
        return np.column_stack([first, (first + 1) % n_electrodes])
    return _explicit_pairs(measurement, n_electrodes, "measurement")


def _explicit_pairs(pattern, n_electrodes, what):
    if isinstance(pattern, str):
        raise InputError(f"scene ert: unknown {what} pattern '{pattern}'; expected "
                         f"{'all, adjacent' if what == 'injection' else 'successive'} or a list of [i, j] pairs")
    try:
        pairs = np.asarray(list(map(list, pattern)), dtype=np.int64)
    except (TypeError, ValueError):
        raise InputError(f"scene ert: {what} pairs must be a list of [i, j] electrode numbers, got {pattern!r}") from None
    if pairs.ndim != 2 or pairs.shape[1] != 2 or len(pairs) == 0:
        raise InputError(f"scene ert: {what} pairs must be a list of [i, j] electrode numbers, got {pairs.tolist()}")
    bad = pairs[(pairs < 1).any(axis=1) | (pairs > n_electrodes).any(axis=1) | (pairs[:, 0] == pairs[:, 1])]
    if len(bad):
        raise InputError(f"scene ert: {what} pair {bad[0].tolist()} names a missing electrode or the same one "
                         f"twice; electrodes are 1-{n_electrodes}")
    return pairs - 1


def channel_names(injections: np.ndarray, measurements: np.ndarray) -> list[str]:
    """`dv_a01_b02_m01_v`: the change of the voltage read at measurement pair m under injection (a, b)."""
    return [f"dv_a{a + 1:02d}_b{b + 1:02d}_m{c + 1:02d}_v" for a, b in injections for c, _ in measurements]
