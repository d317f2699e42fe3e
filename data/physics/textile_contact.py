"""The ERT skin's transducer from fibre-contact physics, and its viscoelastic hysteresis (seed 002 §3.2).

Contact law. A low-resistance patch (20 Ohm/sq) pressed onto the high-resistance base fabric
(20 kOhm/sq) touches it at fibre crossings. Each touching crossing is a Holm constriction spot
(Holm, *Electric Contacts*, 4th ed., 1967, §4: a spot of radius a between conductors of
resistivity rho has resistance rho / 2a; spots far apart add in parallel). How many crossings touch
is counted as Greenwood & Williamson count asperities (Proc. R. Soc. A 295, 1966): each closes at
its own load, so the touching fraction is the distribution function of the closure forces; a
Weibull distribution, phi(F) = 1 - exp(-(F / F_c)^m), gives GW's exponential case at m = 1 and, for
m > 1, few contacts at light load (the air gap between the stacked fabrics, §6). The contact
conductance relative to the base fabric is then c(F) = c_max phi(F), and the base fabric in
parallel with the path through the contacts and the patch (the paper's fig. 3(b) and 5(c)) gives
the normalised resistance

    r(F) = (1 + s c) / (1 + (1 + s) c),      s = patch path / base fabric resistance.

All crossings touching gives the saturated level r_sat = (1 + s c_max) / (1 + (1 + s) c_max); the
patch path is three orders of magnitude below the base (§3.2), so s = 0 and c_max = (1 - r_sat) /
r_sat: the saturation comes from the finite number of crossings.

Fitting the paper. The paper gives an initial sensitivity of -0.0696 1/N in "the early phase of
the compression", saturation "as the compressive force increases over 10 N" at 9.9 %. No law in
which the contact conductance only grows with the load and r is convex (m = 1, the GW exponential
case) can fall from 1 with slope -0.0696 and be near 9.9 % at 10 N: a convex r lies above its
tangent, 1 - 0.0696 F, which reaches 0.099 only at 12.9 N. We read "early phase" as 0-10 N: the
secant slope (r(10 N) - 1) / 10 N is the paper's -0.0696, and the Weibull shape m is the one that
keeps r closest to that straight line over 0-10 N (least squares), so r bends into saturation
above 10 N. `fit_crossing_shape` does this fit; CONTACT holds its result.

Hysteresis. The compression that closes the crossings follows the force through the foam and
knit, a standard linear solid (Zener, *Elasticity and Anelasticity of Metals*, 1948): a spring in
series with a Kelvin-Voigt element. Written in force units, F_eff = (F + D u) / (1 + D) with
tau du/dt = F - u, where D is the relaxation strength (unrelaxed / relaxed stiffness - 1), tau the
creep time and F_eff the force the compression corresponds to at equilibrium; the transducer reads
r(F_eff). Over a haversine load cycle the loading and unloading curves of r against F then differ;
the paper's hysteresis is |A_load - A_unload| / A_load of the areas under them, 8.3 +- 4.7 % over
five frequencies from 1 to 12 Hz. We put tau at the band's logarithmic centre (1 / (2 pi sqrt(12))
s; our choice) and fit D (`fit_relaxation_strength`) so the mean over 1, 3.75, 6.5, 9.25 and 12 Hz
(five equally spaced frequencies, our reading) at a 15 N peak is 8.3 %. The baseline shift (0.57 %
over 50 cycles) is not produced by this solid, which recovers within a cycle; the scene keeps it as
the fed-in `baseline_drift`.
"""
import numpy as np
from scipy.optimize import brentq, minimize_scalar

PAPER = {"initial_slope_per_n": 0.0696, "saturated_fraction": 0.099, "early_phase_n": 10.0,
         "hysteresis_fraction": 0.083, "hysteresis_sd_fraction": 0.047}
FREQUENCIES_HZ = (1.0, 3.75, 6.5, 9.25, 12.0)
CYCLE_PEAK_N = 15.0
# Results of fit_crossing_shape() and fit_relaxation_strength() (tests/data/scenes/test_ert_physics.py re-fits them).
CONTACT = {"initial_slope_per_n": 0.0696, "saturated_fraction": 0.099, "crossing_shape": 2.1008}
FOAM = {"relaxation_strength": 0.2015, "relaxation_time_s": 1.0 / (2.0 * np.pi * np.sqrt(12.0))}


def _ratio(force_n, saturated_fraction, crossing_force_n, crossing_shape):
    c_max = (1.0 - saturated_fraction) / saturated_fraction
    touching = -np.expm1(-(np.maximum(force_n, 0.0) / crossing_force_n) ** crossing_shape)
    return 1.0 / (1.0 + c_max * touching)


def crossing_force_n(initial_slope_per_n, saturated_fraction, crossing_shape, early_phase_n=10.0) -> float:
    """F_c such that the secant slope of r over the early phase is -initial_slope_per_n."""
    target = 1.0 - initial_slope_per_n * early_phase_n
    if not saturated_fraction < target < 1.0:
        raise ValueError(f"r({early_phase_n} N) = {target:.3f} must lie between the saturated level "
                         f"{saturated_fraction} and 1")
    return brentq(lambda fc: _ratio(early_phase_n, saturated_fraction, fc, crossing_shape) - target, 1e-6, 1e6)


def normalised_resistance(force_n, initial_slope_per_n=CONTACT["initial_slope_per_n"],
                          saturated_fraction=CONTACT["saturated_fraction"], crossing_shape=CONTACT["crossing_shape"],
                          early_phase_n=10.0):
    """r(F) of the module docstring, parametrised by the paper's numbers and the Weibull shape."""
    fc = crossing_force_n(initial_slope_per_n, saturated_fraction, crossing_shape, early_phase_n)
    return _ratio(np.asarray(force_n, dtype=float), saturated_fraction, fc, crossing_shape)


def fit_crossing_shape(initial_slope_per_n=PAPER["initial_slope_per_n"],
                       saturated_fraction=PAPER["saturated_fraction"], early_phase_n=PAPER["early_phase_n"]) -> float:
    """The Weibull shape m that keeps r closest (least squares) to the straight line of the
    paper's slope over the early phase."""
    force = np.linspace(0.0, early_phase_n, 101)
    line = 1.0 - initial_slope_per_n * force

    def misfit(m):
        return float(np.mean((normalised_resistance(force, initial_slope_per_n, saturated_fraction, m,
                                                    early_phase_n) - line) ** 2))
    return float(minimize_scalar(misfit, bounds=(1.0, 6.0), method="bounded", options={"xatol": 1e-4}).x)


def cycle(frequency_hz, peak_n=CYCLE_PEAK_N, relaxation_strength=FOAM["relaxation_strength"],
          relaxation_time_s=FOAM["relaxation_time_s"], n=400):
    """One steady-state haversine cycle: (time s, force N, effective force N), loading first."""
    omega = 2.0 * np.pi * frequency_hz
    t = np.linspace(0.0, 1.0 / frequency_hz, 2 * n + 1)
    force = peak_n * 0.5 * (1.0 - np.cos(omega * t))
    wt = omega * relaxation_time_s
    u = peak_n * 0.5 * (1.0 - (np.cos(omega * t) + wt * np.sin(omega * t)) / (1.0 + wt ** 2))
    return t, force, (force + relaxation_strength * u) / (1.0 + relaxation_strength)


def hysteresis_fraction(frequency_hz, peak_n=CYCLE_PEAK_N, relaxation_strength=FOAM["relaxation_strength"],
                        relaxation_time_s=FOAM["relaxation_time_s"], contact=None) -> float:
    """|A_load - A_unload| / A_load of r against F over one cycle (seed 002 §3.2's definition)."""
    t, force, effective = cycle(frequency_hz, peak_n, relaxation_strength, relaxation_time_s)
    r = normalised_resistance(effective, **(contact or CONTACT))
    half = len(t) // 2
    load = np.trapezoid(r[: half + 1], force[: half + 1])
    unload = -np.trapezoid(r[half:], force[half:])
    return float(abs(load - unload) / load)


def fit_relaxation_strength(target=PAPER["hysteresis_fraction"], frequencies_hz=FREQUENCIES_HZ,
                            relaxation_time_s=FOAM["relaxation_time_s"], peak_n=CYCLE_PEAK_N) -> float:
    """D such that the mean hysteresis over `frequencies_hz` is `target`."""
    def mean(d):
        return np.mean([hysteresis_fraction(f, peak_n, d, relaxation_time_s) for f in frequencies_hz]) - target
    return float(brentq(mean, 1e-6, 50.0))


def lag_factor(frequency_hz, unloading, fraction_of_peak, relaxation_strength=FOAM["relaxation_strength"],
               relaxation_time_s=FOAM["relaxation_time_s"]) -> np.ndarray:
    """F_eff / F for presses caught on a haversine cycle at `fraction_of_peak` of its peak, on the
    loading (False) or unloading (True) half (arrays of equal length; the solid is linear, so the
    ratio does not depend on the peak)."""
    fraction = np.clip(np.asarray(fraction_of_peak, dtype=float), 1e-6, 1.0)
    phase = np.arccos(1.0 - 2.0 * fraction)
    phase = np.where(unloading, 2.0 * np.pi - phase, phase)
    wt = 2.0 * np.pi * np.asarray(frequency_hz, dtype=float) * relaxation_time_s
    u = 0.5 * (1.0 - (np.cos(phase) + wt * np.sin(phase)) / (1.0 + wt ** 2))
    return (fraction + relaxation_strength * u) / ((1.0 + relaxation_strength) * fraction)
