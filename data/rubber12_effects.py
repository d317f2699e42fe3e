"""Physical and acquisition effects of the rubber12 sheet, each a function of the batch state.

`state` is a dict of arrays for the whole batch of presses. Field effects (before the
current-flow solve) read and write per-node fields; reading effects (after it) act on the
(n_samples, n_channels) resistances in ohms. Every function takes its parameters as keywords
with physical units in their names, and `rng`, its own random stream.
"""
import numpy as np

from data.contact import flat_punch_force_n, mean_pressure_pa, surface_deflection_mm
from data.errors import InputError


def contact(state, rng, youngs_modulus_pa=1.0e5, poisson_ratio=0.5, thin_layer_correction=True):
    """Flat-punch load and the gel surface's deflection under and around the probe.

    Writes force_n and pressure_pa per press (see data/contact.py for the laws and their
    sources) and deflection_mm per node: Sneddon's profile, d under the punch and
    (2d/pi) asin(a/r) outside it.
    """
    geometry = state["geometry"]
    a, h = geometry["probe_radius_mm"], geometry["gel_thickness_mm"]
    depth = state["depth_mm"]
    state["force_n"] = flat_punch_force_n(depth, a, youngs_modulus_pa, poisson_ratio,
                                          thickness_mm=h if thin_layer_correction else None)
    state["pressure_pa"] = mean_pressure_pa(state["force_n"], a)
    nodes = state["node_xy_mm"]
    distance = np.hypot(nodes[None, :, 0] - state["x_mm"][:, None],
                        nodes[None, :, 1] - state["y_mm"][:, None])
    state["deflection_mm"] = surface_deflection_mm(distance, depth[:, None], a)


def percolation(state, rng, filler_fraction=0.045, percolation_threshold=0.040, exponent=2.0,
                strain_transfer=0.2):
    """Percolation scaling of the sheet's conductivity under compression.

    sigma / sigma_0 = ((p - p_c) / (p_0 - p_c))^t (Balberg, PRL 59, 1987; t ~ 2 in 3-D, 2-6 for
    carbon black). Compression packs filler closer: a through-thickness strain
    eps = strain_transfer * u_z / h_gel reduces the rubber's volume and raises the local filler
    volume fraction to p = p_0 / (1 - eps). `strain_transfer` is the share of the gel's strain
    that the thin rubber layer takes up; it must lie in [0, 1).
    """
    if not percolation_threshold < filler_fraction < 1.0:
        raise InputError(f"percolation: need percolation_threshold < filler_fraction < 1, got "
                         f"{percolation_threshold} and {filler_fraction}")
    if not 0.0 <= strain_transfer < 1.0:
        raise InputError(f"percolation: strain_transfer must lie in [0, 1), got {strain_transfer}")
    if "deflection_mm" not in state:
        return  # nothing compresses the sheet: conductivity stays at its rest value
    strain = strain_transfer * state["deflection_mm"] / state["geometry"]["gel_thickness_mm"]
    fraction = filler_fraction / (1.0 - strain)
    relative = ((fraction - percolation_threshold) / (filler_fraction - percolation_threshold)) ** exponent
    state["conductance_scale"] = state.get("conductance_scale", 1.0) * relative


def temperature_drift(state, rng, coefficient_per_c=0.004, ambient_c=25.0, spread_c=1.0,
                      reference_c=25.0):
    """Resistance drift with temperature: R <- R (1 + alpha (T - T_ref)).

    The lab held 25 +/- 1 C and saw absolute resistance drift 3-5 % per 10 C (physics notes,
    seed 000), so alpha defaults to 0.4 %/C. Each press gets its own T ~ U(ambient +/- spread).
    """
    n = state["resistance_ohm"].shape[0]
    state["temperature_c"] = ambient_c + rng.uniform(-spread_c, spread_c, size=n)
    state["resistance_ohm"] = state["resistance_ohm"] * (
        1.0 + coefficient_per_c * (state["temperature_c"] - reference_c))[:, None]


def adc(state, rng, bits=12, supply_v=3.3, reference_resistor_ohm=1.0e4, noise_lsb=1.0,
        samples_averaged=50):
    """Read each channel through a voltage divider and an N-bit ADC, as the lab did.

    V = V_s R / (R + R_ref) is sampled `samples_averaged` times (100 Hz, the last 0.5 s of a
    5 s hold) with Gaussian noise of `noise_lsb` LSB, each sample rounded to a code, and the
    mean code turned back into ohms with R = R_ref c / (c_max - c). The mean code is kept half
    an LSB inside the scale so a saturated channel reads a large finite resistance, not inf.
    """
    if bits < 1 or samples_averaged < 1:
        raise InputError(f"adc: bits and samples_averaged must be >= 1, got {bits}, {samples_averaged}")
    full_scale = 2**bits - 1
    r = state["resistance_ohm"]
    ideal = full_scale * r / (r + reference_resistor_ohm)
    noise = rng.normal(0.0, noise_lsb, size=(samples_averaged,) + r.shape)
    codes = np.clip(np.rint(ideal[None] + noise), 0, full_scale).mean(axis=0)
    codes = np.clip(codes, 0.5, full_scale - 0.5)
    state["resistance_ohm"] = reference_resistor_ohm * codes / (full_scale - codes)


FIELD_EFFECTS = {"contact": contact, "percolation": percolation}
READING_EFFECTS = {"temperature_drift": temperature_drift, "adc": adc}
EFFECTS = {**FIELD_EFFECTS, **READING_EFFECTS}
