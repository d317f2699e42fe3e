"""Units in column names and the values they can physically take.

Touchstone names every channel, target and label column with its unit as the last
underscore-separated word (`r_01_ohm`, `depth_mm`, `pressure_pa`, `force_level_n`,
`triboelectric_na`). This module reads that word, case-insensitively, and says which quantity the
column holds and the closed interval its values can lie in: a reading outside it is a broken
file or a wrong unit, not data to learn from. The validators refuse such values
(data/table_files.py, data/recording_files.py); interval bounds may be clipped to the same range.

    physical_range("r_03_ohm")    -> PhysicalRange("resistance", 0.0, inf, ...)
    physical_range("shear_x_n")   -> None   (a force component: any sign)
    physical_range("rmc_r0_c3")   -> None   (no unit word: no rule)

Only what holds for every sensor is a rule; anything signed or unknown is left alone:
- a word that is not a unit below (`c3`, `norm`, `counts`) gives no rule;
- a difference is signed whatever its unit: a name whose first word is `d`, `dv`, `dr` or
  `delta`, or with the word `delta`, `change` or `diff` in it (the ERT scene's `dv_a01_b02_m03_v`);
- lengths and forces are signed as coordinates and components (`x_mm`, `shear_x_n`, `normal_n`:
  a load cell also reads tension), and non-negative only where the name says the column is a
  magnitude (LENGTH_MAGNITUDES, FORCE_MAGNITUDES).
Ranges are in the column's own unit (hence per suffix, not per quantity: -273.15 is degrees
Celsius). The scenes' column names (data/scenes/*.py) are checked against these rules by
tests/test_training_input.py, so simulated data is never refused.
"""
import math
import re
from dataclasses import dataclass

import numpy as np

INF = math.inf


@dataclass(frozen=True)
class PhysicalRange:
    quantity: str
    low: float
    high: float
    why: str

    def describe(self) -> str:
        if self.high == INF:
            return f"a {self.quantity} is >= {self.low:g} ({self.why})"
        return f"a {self.quantity} lies in [{self.low:g}, {self.high:g}] ({self.why})"


# Why each bound is physical, once per quantity.
_RESISTANCE = ("resistance", "a passive material dissipates power, so V = IR with R >= 0; negative "
                             "resistance is only ever the small-signal slope of an active circuit")
_CAPACITANCE = ("capacitance", "C = Q / V >= 0 for any capacitor: its stored energy CV^2/2 cannot be "
                               "negative; a change of capacitance is a delta_ column")
_PRESSURE = ("pressure", "an absolute pressure or the pressure a contact exerts is >= 0; a gauge or "
                         "differential reading is a delta_ column")
_FREQUENCY = ("frequency", "events per second cannot be negative")
_MASS = ("mass", "mass is never negative")
_LENGTH = ("length", "a depth, thickness, radius, diameter, distance or width is a size, never "
                     "negative; positions (x_mm) are signed coordinates")
_FORCE = ("force magnitude", "a force's magnitude, a total force or a force level is >= 0; components "
                             "(shear_x_n, normal_n) are signed")

# unit word -> (quantity, why, low, high), for quantities that are bounded whatever the name's stem.
BOUNDED_UNITS = {
    **{unit: (*_RESISTANCE, 0.0, INF) for unit in ("ohm", "ohms", "kohm", "mohm", "gohm")},
    **{unit: (*_CAPACITANCE, 0.0, INF) for unit in ("pf", "nf", "uf", "ff")},
    **{unit: (*_PRESSURE, 0.0, INF) for unit in ("pa", "kpa", "mpa", "hpa", "bar", "mbar", "psi")},
    **{unit: (*_FREQUENCY, 0.0, INF) for unit in ("hz", "khz", "mhz")},
    **{unit: (*_MASS, 0.0, INF) for unit in ("kg",)},
    "degc": ("temperature", "nothing is colder than absolute zero, -273.15 degrees Celsius", -273.15, INF),
}
# Signed whatever the stem (listed so that a reader sees they were considered, not forgotten):
# voltages (v, mv, uv), currents (a, ma, ua, na), time (s, ms, us), angles (deg, rad), counts.
SIGNED_UNITS = ("v", "mv", "uv", "kv", "a", "ma", "ua", "na", "s", "ms", "us", "deg", "rad", "counts")
# Units whose sign depends on what the stem names.
LENGTH_UNITS = ("m", "cm", "mm", "um", "nm")
FORCE_UNITS = ("n", "mn", "kn")
# The stem's last word (digits after it allowed: force2_n) that makes a column a magnitude.
LENGTH_MAGNITUDES = ("depth", "thickness", "radius", "diameter", "distance", "width", "indentation")
FORCE_MAGNITUDES = ("force",)   # force_n, force2_n, grip_force_n; also the stem force_level
DIFFERENCE_FIRST_WORDS = ("d", "dv", "dr", "delta")
DIFFERENCE_WORDS = ("delta", "change", "diff")


def unit_of(column: str) -> str | None:
    """The unit word of a column name (lower case), or None without an underscore."""
    stem, _, unit = str(column).rpartition("_")
    return unit.lower() if stem else None


def _is_difference(words: list[str]) -> bool:
    return words[0] in DIFFERENCE_FIRST_WORDS or any(w in DIFFERENCE_WORDS for w in words)


def _names_magnitude(words: list[str], magnitudes: tuple[str, ...]) -> bool:
    if re.sub(r"\d+$", "", words[-1]) in magnitudes:
        return True
    return "force" in magnitudes and words[-2:] == ["force", "level"]


def physical_range(column: str) -> PhysicalRange | None:
    """The interval a column's values can physically lie in, from its name; None: no rule."""
    unit = unit_of(column)
    if unit is None:
        return None
    words = str(column).lower().rsplit("_", 1)[0].split("_")
    if _is_difference(words):
        return None
    if unit in BOUNDED_UNITS:
        quantity, why, low, high = BOUNDED_UNITS[unit]
        return PhysicalRange(quantity, low, high, why)
    if unit in LENGTH_UNITS and _names_magnitude(words, LENGTH_MAGNITUDES):
        return PhysicalRange(_LENGTH[0], 0.0, INF, _LENGTH[1])
    if unit in FORCE_UNITS and _names_magnitude(words, FORCE_MAGNITUDES):
        return PhysicalRange(_FORCE[0], 0.0, INF, _FORCE[1])
    return None


def first_outside(values, column: str):
    """(flat index, value, rule) of the first value outside the column's physical range, or None
    (also for a column without a rule). NaN is not this check's business: it compares False."""
    rule = physical_range(column)
    if rule is None:
        return None
    values = np.asarray(values)
    outside = (values < rule.low) | (values > rule.high)
    if not outside.any():
        return None
    k = int(np.flatnonzero(outside)[0])
    return k, values.flat[k], rule
