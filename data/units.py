"""Units in column names and the values they can physically take.

Touchstone names every channel, target and label column with its unit as the last
underscore-separated word (`r_01_ohm`, `depth_mm`, `pressure_pa`, `force_level_n`,
`triboelectric_na`). This module reads that word, case-insensitively, and says which quantity the
column holds and the closed interval its values can lie in: a reading outside it is a broken
file or a wrong unit, not data to learn from. The validators refuse such values
(data/readers/table_reader.py, data/readers/recording_reader.py); a regression's predictions and interval
bounds are clipped to the same range (clip_columns: runs/regression.py, export/onnx_predictor.py).

    physical_range("r_03_ohm")    -> PhysicalRange("resistance", 0.0, inf, ...)
    physical_range("shear_x_n")   -> None   (a force component: any sign)
    physical_range("rmc_r0_c3")   -> None   (no unit word: no rule)

Only what holds for every sensor is a rule; anything signed or unknown is left alone:
- a word that is not a unit below (`c3`, `norm`, `counts`) gives no rule;
- a difference is signed whatever its unit: a name whose first word is `d`, `dv`, `dr` or
  `delta`, or with the word `delta`, `change` or `diff` in it (the ERT scene's `dv_a01_b02_m03_v`);
- lengths and forces are signed as coordinates and components (`x_mm`, `shear_x_n`, `normal_n`:
  a load cell also reads tension), and non-negative only where the name says the column is a
  magnitude (LENGTH_MAGNITUDES, FORCE_MAGNITUDES, FORCE_MAGNITUDE_STEMS).
Ranges are in the column's own unit (hence per suffix, not per quantity: -273.15 is degrees
Celsius). The scenes' column names (data/scenes/*.py) are checked against these rules by
tests/data/test_training_input.py, so simulated data is never refused.
"""
import math
import re
from dataclasses import dataclass

import numpy as np

INF = math.inf
# Stems whose last word (digits after it allowed: force2_n) names a size or a magnitude; the
# stem force_level too (FORCE_MAGNITUDE_STEMS). Lengths and forces are otherwise signed.
LENGTH_MAGNITUDES = ("depth", "thickness", "radius", "diameter", "distance", "width", "indentation")
FORCE_MAGNITUDES = ("force",)
FORCE_MAGNITUDE_STEMS = ("force_level",)
# A difference (`delta_r_ohm`, the ERT scene's `dv_a01_b02_m03_v`) is signed whatever its unit.
DIFFERENCE_FIRST_WORDS = ("d", "dv", "dr", "delta")
DIFFERENCE_WORDS = ("delta", "change", "diff")


@dataclass(frozen=True)
class Unit:
    """What a unit word says: the quantity, and the interval its values physically lie in (in
    this unit), for every column (`magnitudes` empty) or only for stems naming a magnitude."""
    quantity: str
    low: float = -INF
    high: float = INF
    why: str = "signed: no bound"
    magnitudes: tuple = ()


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


def _units(words, quantity, **rule) -> dict:
    return {word: Unit(quantity, **rule) for word in words}


# The one table: unit word -> quantity and physical range, each bound with why it is physical.
UNITS = {
    **_units(("ohm", "ohms", "kohm", "mohm", "gohm"), "resistance", low=0.0,
             why="a passive material dissipates power, so V = IR with R >= 0; negative resistance is only "
                 "ever the small-signal slope of an active circuit"),
    **_units(("pf", "nf", "uf", "ff"), "capacitance", low=0.0,
             why="C = Q / V >= 0 for any capacitor, its stored energy CV^2/2 cannot be negative; a change of "
                 "capacitance is a delta_ column"),
    **_units(("pa", "kpa", "mpa", "hpa", "bar", "mbar", "psi"), "pressure", low=0.0,
             why="an absolute pressure or the pressure a contact exerts is >= 0; a gauge or differential "
                 "reading is a delta_ column"),
    **_units(("hz", "khz", "mhz"), "frequency", low=0.0, why="events per second cannot be negative"),
    **_units(("kg",), "mass", low=0.0, why="mass is never negative"),
    "degc": Unit("temperature", low=-273.15, why="nothing is colder than absolute zero, -273.15 degrees Celsius"),
    **_units(("m", "cm", "mm", "um", "nm"), "length", low=0.0, magnitudes=LENGTH_MAGNITUDES,
             why="a depth, thickness, radius, diameter, distance or width is a size, never negative; "
                 "positions (x_mm) are signed coordinates"),
    **_units(("n", "mn", "kn"), "force", low=0.0, magnitudes=FORCE_MAGNITUDES,
             why="a force's magnitude, a total force or a force level is >= 0; components (shear_x_n, "
                 "normal_n: a load cell also reads tension) are signed"),
    # Signed: listed so that a reader sees they were considered, and for the quantity they name.
    **_units(("v", "mv", "uv", "kv"), "voltage"),
    **_units(("a", "ma", "ua", "na"), "current"),
    **_units(("s", "ms", "us"), "time"),
    **_units(("deg", "rad"), "angle"),
    "counts": Unit("count"),
}


def unit_of(column: str) -> str | None:
    """The unit word of a column name (lower case), or None without an underscore."""
    stem, _, unit = str(column).rpartition("_")
    return unit.lower() if stem else None


def physical_range(column: str) -> PhysicalRange | None:
    """The interval a column's values can physically lie in, from its name; None: no rule (an
    unknown or signed unit, a difference, a length or force that is not a magnitude)."""
    unit = UNITS.get(unit_of(column))
    if unit is None or (unit.low == -INF and unit.high == INF):
        return None
    stem = str(column).lower().rpartition("_")[0]
    words = stem.split("_")
    if words[0] in DIFFERENCE_FIRST_WORDS or any(w in DIFFERENCE_WORDS for w in words):
        return None
    names_magnitude = (re.sub(r"\d+$", "", words[-1]) in unit.magnitudes
                       or (unit.quantity == "force" and stem.endswith(FORCE_MAGNITUDE_STEMS)))
    if unit.magnitudes and not names_magnitude:
        return None
    return PhysicalRange(unit.quantity, unit.low, unit.high, unit.why)


def clip_to_range(values, column: str) -> np.ndarray:
    """`values` clipped to the column's physical range (unchanged for a column without a rule): a
    prediction or an interval bound beyond it (a pressure below 0 Pa) is never nearer the truth."""
    rule = physical_range(column)
    values = np.asarray(values, dtype=np.float64)
    return values if rule is None else np.clip(values, rule.low, rule.high)


def clip_columns(values, columns) -> np.ndarray:
    """(n, len(columns)) values, each column clipped to its physical range (clip_to_range)."""
    values = np.asarray(values, dtype=np.float64).reshape(-1, len(columns))
    return np.column_stack([clip_to_range(values[:, k], column) for k, column in enumerate(columns)])


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
