"""Physical and acquisition effects of the rubber12 sheet. A scene runs only those it lists.

Field effects act on one chunk of presses before the current-flow solve, on per-node fields
of shape (n_presses, n_nodes); they are deterministic functions of the press (randomness
belongs to the acquisition). Reading effects act after the solve on the whole data set's
(n_presses, n_channels) readings and draw from their own random generator `rng`. Every
parameter is a keyword with its unit in its name.
"""
import numpy as np

from data.physics.contact_mechanics import flat_punch_force_n, mean_pressure_pa, surface_deflection_mm
from data.errors import InputError
from data.minmax_scaling import MinMaxScaling


def _needs(state, key, effect, provider):
    if key not in state:
        raise InputError(f"scene rubber12: effect '{effect}' needs '{provider}' listed too")
    return state[key]


# -- field effects --------------------------------------------------------------------------
def contact(state, youngs_modulus_pa=1.0e5, poisson_ratio=0.5, thin_layer_correction=True,
            strain_transfer=0.2, spread_mm=4.0):
    """Flat-punch load on the gel, and the compression of the rubber sheet under and around it.

    force_n = 2 a E* d (x the thin-layer factor) and pressure_pa = F / (pi a^2): see
    data/physics/contact_mechanics.py for the laws and their sources. The sheet follows the gel's surface,
    which sinks by d under the punch and by Sneddon's (2d/pi) asin(a/r) around it. A bonded
    layer of thickness h carries that deflection only a short way past the rim (the
    half-space's slow 1/r tail needs an unbounded body), so the profile is tapered to zero
    over `spread_mm` beyond the rim with a raised-cosine window; this also keeps the patch of
    changed conductance small, which the patch solver relies on. The sheet's compressive
    strain is strain_transfer * u_z / h: the share of the gel's strain the rubber takes up.
    """
    geometry = state["geometry"]
    a, h = geometry["probe_radius_mm"], geometry["gel_thickness_mm"]
    if not 0.0 <= strain_transfer < 1.0 or spread_mm < 0:
        raise InputError(f"scene rubber12: contact needs 0 <= strain_transfer < 1 and spread_mm >= 0, "
                         f"got {strain_transfer} and {spread_mm}")
    depth = state["depth_mm"]
    state["force_n"] = flat_punch_force_n(depth, a, youngs_modulus_pa, poisson_ratio,
                                          thickness_mm=h if thin_layer_correction else None)
    state["pressure_pa"] = mean_pressure_pa(state["force_n"], a)
    nodes = state["node_xy_mm"]
    distance = np.hypot(nodes[None, :, 0] - state["x_mm"][:, None], nodes[None, :, 1] - state["y_mm"][:, None])
    beyond = np.clip((distance - a) / max(spread_mm, 1e-12), 0.0, 1.0)
    taper = 0.5 * (1.0 + np.cos(np.pi * beyond))
    deflection = surface_deflection_mm(distance, depth[:, None], a) * taper
    state["sheet_strain"] = strain_transfer * deflection / h


def hysteresis(state, loss_fraction=0.10):
    """Loading and unloading paths differ: on the way down the rubber keeps more compression.

    Carbon-black elastomers and FSR-like films show about +10 % hysteresis (physics notes).
    A press reached from a deeper press at the same point (protocol sequence `up_down`)
    carries (1 + loss_fraction) times the strain of the same press on the way up.
    """
    strain = _needs(state, "sheet_strain", "hysteresis", "contact")
    state["sheet_strain"] = strain * (1.0 + loss_fraction * state["unloading"][:, None])


def percolation(state, filler_fraction=0.045, percolation_threshold=0.040, exponent=2.0):
    """Percolation scaling of conductivity as compression packs the filler closer.

    sigma / sigma_0 = ((p - p_c) / (p_0 - p_c))^t (Balberg, PRL 59, 1987; t ~ 1.3 in 2-D,
    2 in 3-D, 2-6 for carbon black), with the local filler volume fraction raised by the
    layer's compressive strain eps to p = p_0 / (1 - eps).
    """
    if not percolation_threshold < filler_fraction < 1.0:
        raise InputError(f"scene rubber12: percolation needs percolation_threshold < filler_fraction < 1, "
                         f"got {percolation_threshold} and {filler_fraction}")
    strain = _needs(state, "sheet_strain", "percolation", "contact")
    fraction = filler_fraction / (1.0 - strain)
    relative = ((fraction - percolation_threshold) / (filler_fraction - percolation_threshold)) ** exponent
    state["conductance_scale"] = state.get("conductance_scale", 1.0) * relative


def tunneling(state, barrier_height_ev=0.5, gap_nm=1.5):
    """Tunnelling across the polymer gaps between filler particles (Simmons, J. Appl. Phys. 34,
    1963; Zhang et al., J. Polym. Sci. B 38, 2000): junction resistance R ~ s exp(gamma s),
    gamma = 10.25 nm^-1 sqrt(phi / 1 eV). Compression by eps shrinks the gap to s0 (1 - eps),
    so R / R0 = (1 - eps) exp(-gamma s0 eps); conductance scales by the inverse.
    """
    strain = _needs(state, "sheet_strain", "tunneling", "contact")
    gamma_per_nm = 10.25 * np.sqrt(barrier_height_ev)
    ratio = (1.0 - strain) * np.exp(-gamma_per_nm * gap_nm * strain)
    state["conductance_scale"] = state.get("conductance_scale", 1.0) / ratio


# -- reading effects ------------------------------------------------------------------------
def electrode_contact(state, rng, resistance_ohm=200.0, asymmetry=0.05):
    """Contact resistance of each electrode, in series with both ends of every two-terminal
    reading. Each electrode's value is drawn once per sensor as resistance (1 + asymmetry N(0,1)):
    the only thing that breaks the sheet's mirror symmetry."""
    n_electrodes = int(state["pairs"].max()) + 1
    per_electrode = np.maximum(resistance_ohm * (1.0 + asymmetry * rng.standard_normal(n_electrodes)), 0.0)
    pairs = state["pairs"]
    state["resistance_ohm"] = state["resistance_ohm"] + per_electrode[pairs[:, 0]] + per_electrode[pairs[:, 1]]


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


def _codes_to_ohm(codes, full_scale, reference_resistor_ohm):
    # Keep the mean code half an LSB inside the scale: a saturated channel reads a large
    # finite resistance, not inf or a negative value.
    codes = np.clip(codes, 0.5, full_scale - 0.5)
    return reference_resistor_ohm * codes / (full_scale - codes)


def adc(state, rng, bits=12, reference_resistor_ohm=1.0e4, noise_lsb=1.0, samples_averaged=50,
        spike_probability=0.0, spike_lsb=200.0):
    """Read each channel through a voltage divider and an N-bit ADC, as the lab did.

    The code is c = c_max R / (R + R_ref) (ratiometric, so the supply voltage cancels), sampled
    `samples_averaged` times (100 Hz, the last 0.5 s of a 5 s hold) with Gaussian noise of
    `noise_lsb` LSB and, with `spike_probability`, interference spikes of +/- `spike_lsb`; each
    sample is rounded to an integer code, and the mean code turned back into ohms,
    R = R_ref c / (c_max - c).
    """
    if bits < 1 or samples_averaged < 1:
        raise InputError(f"scene rubber12: adc needs bits and samples_averaged >= 1, got {bits}, {samples_averaged}")
    full_scale = 2**bits - 1
    r = state["resistance_ohm"]
    ideal = full_scale * r / (r + reference_resistor_ohm)
    noise = rng.normal(0.0, noise_lsb, size=(samples_averaged,) + r.shape)
    if spike_probability > 0:
        spikes = rng.random(noise.shape) < spike_probability
        noise += spikes * spike_lsb * rng.choice([-1.0, 1.0], size=noise.shape)
    codes = np.clip(np.rint(ideal[None] + noise), 0, full_scale)
    state["adc"] = {"codes": codes, "full_scale": full_scale, "reference_resistor_ohm": reference_resistor_ohm}
    state["resistance_ohm"] = _codes_to_ohm(codes.mean(axis=0), full_scale, reference_resistor_ohm)


def outlier_rejection(state, rng, sigmas=3.0):
    """The lab's 3-sigma rule: within each channel's averaging window, drop samples further than
    `sigmas` standard deviations from the window's mean before averaging."""
    reading = _needs(state, "adc", "outlier_rejection", "adc")
    codes = reading["codes"]
    mean, std = codes.mean(axis=0), codes.std(axis=0)
    keep = np.abs(codes - mean) <= sigmas * std + 1e-12
    kept_mean = (codes * keep).sum(axis=0) / np.maximum(keep.sum(axis=0), 1)
    state["resistance_ohm"] = _codes_to_ohm(kept_mean, reading["full_scale"], reading["reference_resistor_ohm"])


def minmax_normalize(state, rng):
    """Min-max normalisation of each channel over the data set, as the lab did: readings become
    unitless in [0, 1] (channel names change from r_XX_ohm to r_XX_norm). A channel that never
    changes maps to 0. The per-channel minimum and span are kept (`state["normalisation"]`, then
    the SensorTable's `normalisation`): a model trained on these channels applies them to raw
    ohms when deployed (data/minmax_scaling.py)."""
    scaling = MinMaxScaling.fit(state["resistance_ohm"], state["channels"])
    state["resistance_ohm"] = scaling.normalise(state["resistance_ohm"])
    state["channels"] = [name.removesuffix("_ohm") + "_norm" for name in state["channels"]]
    state["normalisation"] = scaling


FIELD_EFFECTS = {"contact": contact, "hysteresis": hysteresis, "percolation": percolation, "tunneling": tunneling}
READING_EFFECTS = {"electrode_contact": electrode_contact, "temperature_drift": temperature_drift,
                   "adc": adc, "outlier_rejection": outlier_rejection, "minmax_normalize": minmax_normalize}
EFFECTS = {**FIELD_EFFECTS, **READING_EFFECTS}
