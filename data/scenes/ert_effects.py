"""Physical and acquisition effects of the ERT textile skin (seed 002). A scene runs only those it lists.

Three stages, in the sensor's chain order:
- sensor effects change the sensor once per scene (per seed): `specimen_variation` (each patch's
  base resistance and sensitivity), `electrode_position_error` (where the sewn electrodes
  really are);
- press effects turn indenters into a per-patch conductance factor: `foam_spread` (how the
  neoprene shares a load among patches), `hysteresis` (loading vs unloading branch),
  `contact_resistance` (the patch-on-fabric transducer curve; without it no press changes
  the sheet, so a scene without it is silent);
- reading effects act on the voltages: `baseline_drift`, `adc_noise`.
Every parameter is a keyword with its unit in its name; each effect draws from its own
generator `rng` (data/scenes/contract.py).
"""
import numpy as np

from common.errors import InputError


def _fail(effect, message):
    raise InputError(f"scene ert: effect '{effect}': {message}")


# -- sensor effects ---------------------------------------------------------------------------
def specimen_variation(state, rng, base_resistance_spread=0.10, sensitivity_spread=0.33):
    """Patch-to-patch spread of the fabric: seed 002 §3.2 measured initial specimen resistances
    of 17.12 +- 1.75 kOhm (about 10 %) and initial sensitivities of -0.0696 +- 0.0232 1/N
    (33 %). Each patch draws a lognormal factor on its base sheet resistance and on its
    sensitivity, fixed for the sensor (one draw per seed)."""
    if base_resistance_spread < 0 or sensitivity_spread < 0:
        _fail("specimen_variation", f"spreads must be >= 0, got {base_resistance_spread} and {sensitivity_spread}")
    n = state["n_patches"]
    state["patch_base_resistance_scale"] = np.exp(rng.normal(0.0, base_resistance_spread, n))
    state["patch_sensitivity_scale"] = np.exp(rng.normal(0.0, sensitivity_spread, n))


def electrode_position_error(state, rng, sd_mm=2.0):
    """Sewn electrodes sit a little off their drawn positions (hand stitching on fabric). Each
    electrode moves by N(0, sd_mm) per axis, edge electrodes along their edge only, all kept on
    the sheet; the grid then snaps them to nodes, so errors below half a node spacing vanish."""
    if sd_mm < 0:
        _fail("electrode_position_error", f"sd_mm must be >= 0, got {sd_mm}")
    xy = np.array(state["electrodes_mm"], dtype=float)
    side = state["side_mm"]
    on_edge = (xy == 0.0) | (xy == side)
    moved = xy + rng.normal(0.0, sd_mm, xy.shape) * ~on_edge
    state["electrodes_mm"] = np.clip(moved, 0.0, side)


# -- press effects ----------------------------------------------------------------------------
def foam_spread(state, spread_per_thickness=1.0):
    """The 4 mm neoprene spreads each indenter's load over neighbouring patches. A load on an
    elastic layer reaches the layer below spread over a width of the order of the layer's
    thickness (Johnson, *Contact Mechanics*, 1985, §3 and ch. 5 on layers); modelled as a
    Gaussian of sd = spread_per_thickness x foam thickness convolved with the indenter's
    footprint. Without this effect each patch carries the load on its own footprint."""
    if spread_per_thickness < 0:
        _fail("foam_spread", f"spread_per_thickness must be >= 0, got {spread_per_thickness}")
    state["spread_sd_mm"] = spread_per_thickness * state["geometry"]["foam_thickness_mm"]


def hysteresis(state, rng, mean_fraction=0.083, sd_fraction=0.047):
    """Loading and unloading curves differ by 8.3 +- 4.7 % in area (seed 002 §3.2, 1-12 Hz). A
    press is caught on the loading or the unloading branch at random; on unloading the
    transducer behaves as if loaded (1 + h) times harder, h ~ N(mean, sd) clipped at 0."""
    if mean_fraction < 0 or sd_fraction < 0:
        _fail("hysteresis", f"fractions must be >= 0, got {mean_fraction} and {sd_fraction}")
    n = len(state["patch_force_n"])
    unloading = rng.random(n) < 0.5
    h = np.clip(rng.normal(mean_fraction, sd_fraction, n), 0.0, None)
    state["patch_force_n"] = state["patch_force_n"] * (1.0 + h * unloading)[:, None]


def contact_resistance(state, initial_slope_per_n=0.0696, saturated_fraction=0.099):
    """The transducer (seed 002 §3.2, fig. 5): pressing a 20 Ohm/sq patch into the 20 kOhm/sq
    base lowers the contact resistance between them and opens a parallel path, so the local
    normalised resistance falls from 1 with initial slope -0.0696 1/N and saturates at 9.9 %.
    A saturating exponential with those two numbers:
        r(F) = r_sat + (1 - r_sat) exp(-k F / (1 - r_sat)),  dr/dF(0) = -k,
    and the patch's sheet conductance becomes base / r (the parallel path, fig. 5(c))."""
    if initial_slope_per_n < 0 or not 0.0 < saturated_fraction <= 1.0:
        _fail("contact_resistance", f"needs initial_slope_per_n >= 0 and 0 < saturated_fraction <= 1, "
                                    f"got {initial_slope_per_n} and {saturated_fraction}")
    k = initial_slope_per_n * state["patch_sensitivity_scale"][None, :]
    span = 1.0 - saturated_fraction
    exponent = k * state["patch_force_n"] / span if span > 0 else np.zeros_like(state["patch_force_n"])
    ratio = saturated_fraction + span * np.exp(-exponent)
    state["patch_conductance_factor"] = 1.0 / ratio


# -- reading effects --------------------------------------------------------------------------
def baseline_drift(state, rng, fraction_per_50_presses=0.0057):
    """The fabric's unloaded resistance wanders: 0.57 % of its initial value over 50 cycles
    (seed 002 §3.2). Each patch's base conductance takes a random walk over the press order
    whose sd after 50 presses is that fraction; the voltages move by J_patch delta (the
    linearised forward model, eq. 3; the walk is far too small for the nonlinearity to matter).
    The baseline frame is taken before each recording's first press, so the drift is not removed
    within a recording; it restarts with each new recording (state["recording"])."""
    if fraction_per_50_presses < 0:
        _fail("baseline_drift", f"fraction_per_50_presses must be >= 0, got {fraction_per_50_presses}")
    jacobian = state["patch_jacobian"]()                      # (n_channels, n_patches)
    n = len(state["voltage_v"])
    steps = rng.normal(0.0, fraction_per_50_presses / np.sqrt(50.0), (n, jacobian.shape[1]))
    walk = np.cumsum(steps, axis=0)
    recording = np.asarray(state.get("recording", np.zeros(n, dtype=int)))
    starts = np.flatnonzero(np.r_[True, recording[1:] != recording[:-1]])
    walk -= np.repeat(walk[starts] - steps[starts], np.diff(np.r_[starts, n]), axis=0)   # restart per recording
    state["voltage_v"] = state["voltage_v"] + walk @ jacobian.T


def adc_noise(state, rng, noise_v=2.0e-4, bits=24, full_scale_v=10.0):
    """White noise on every voltage (the analogue front end and multiplexer settling at 333 kHz),
    then a `bits`-bit ADC over +-full_scale_v (seed 002 §3.4: 24-bit), applied to every frame
    including the unloaded baseline frame."""
    if noise_v < 0 or bits < 1 or full_scale_v <= 0:
        _fail("adc_noise", f"needs noise_v >= 0, bits >= 1, full_scale_v > 0, got {noise_v}, {bits}, {full_scale_v}")
    lsb = 2.0 * full_scale_v / 2 ** bits
    for key in ("voltage_v", "baseline_v"):
        noisy = state[key] + rng.normal(0.0, noise_v, state[key].shape)
        state[key] = np.clip(np.round(noisy / lsb) * lsb, -full_scale_v, full_scale_v)


SENSOR_EFFECTS = {"specimen_variation": specimen_variation, "electrode_position_error": electrode_position_error}
PRESS_EFFECTS = {"foam_spread": foam_spread, "hysteresis": hysteresis, "contact_resistance": contact_resistance}
READING_EFFECTS = {"baseline_drift": baseline_drift, "adc_noise": adc_noise}
EFFECTS = {**SENSOR_EFFECTS, **PRESS_EFFECTS, **READING_EFFECTS}
RANDOM_EFFECTS = {"specimen_variation", "electrode_position_error", "hysteresis", "baseline_drift", "adc_noise"}
