"""Physical and acquisition effects of the ERT textile skin (seed 002). A scene runs only those it lists.

Three stages, in the sensor's chain order:
- sensor effects change the sensor once per scene (per seed): `specimen_variation` (each patch's
  base resistance and sensitivity), `electrode_position_error` (where the sewn electrodes
  really are), `fabric_anisotropy` (the knit conducts differently along courses and wales);
- press effects turn indenters into a conductance factor per patch, or per grid node with
  `local_contact` (the patch shorts only the fabric it touches): `foam_spread` (how the
  neoprene shares a load among patches), `hysteresis` (loading vs unloading branch, a fed-in
  fraction) or `viscoelastic_hysteresis` (the foam's standard linear solid,
  data/physics/textile_contact.py), `contact_resistance` (the fed-in transducer curve) or
  `textile_contact` (Holm spots counted Greenwood-Williamson style in parallel with the base
  fabric); without one of the two transducers no press changes the sheet, so the scene is silent;
- reading effects act on the voltages: `electrode_contact_impedance` (stitched electrodes'
  contact resistance and its drift), `baseline_drift`, `adc_noise`.
Every parameter is a keyword with its unit in its name; each effect draws from its own
generator `rng` (data/scenes/contract.py).
"""
import numpy as np

from common.errors import InputError
from data.physics.textile_contact import CONTACT, FOAM, lag_factor, normalised_resistance


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


def fabric_anisotropy(state, rng, ratio=2.0):
    """The knitted base fabric conducts differently along its courses (x) and wales (y): the paper
    calls both fabrics orthotropic (seed 002 §6) but gives no ratio, so `ratio` (sheet conductance
    along x / along y, geometric mean kept at the nominal value) is our choice; nothing is drawn
    (`rng` is the sensor stage's signature). The reconstruction, built from the nominal
    isotropic sheet, does not know it."""
    if not ratio > 0:
        _fail("fabric_anisotropy", f"ratio must be > 0, got {ratio}")
    state["anisotropy_ratio"] = float(ratio)


# -- press effects ----------------------------------------------------------------------------
def local_contact(state):
    """The low-resistance patch shorts only the base fabric it touches, not its whole 20 x 20 mm
    square: a 20 Ohm/sq patch is an equipotential next to the 20 kOhm/sq base (seed 002 §3.1,
    table 1), connected to it through the fibre contacts under the load (fig. 3(b)), so the
    parallel path covers the pressed area (the footprint spread by the foam) within the patch.
    The transducer law then acts on each grid node's local load, expressed as the force that
    would load a whole patch to the same pressure (the paper's curve was taken with the patch
    pressed over its entire surface, §3.2). Without it every node of a loaded patch changes alike."""
    state["local"] = True


def foam_spread(state, spread_per_thickness=1.0):
    """The 4 mm neoprene spreads each indenter's load over neighbouring patches. A load on an
    elastic layer reaches the layer below spread over a width of the order of the layer's
    thickness (Johnson, *Contact Mechanics*, 1985, §3 and ch. 5 on layers); modelled as a
    Gaussian of sd = spread_per_thickness x foam thickness convolved with the indenter's
    footprint. Without this effect each patch carries the load on its own footprint."""
    if spread_per_thickness < 0:
        _fail("foam_spread", f"spread_per_thickness must be >= 0, got {spread_per_thickness}")
    state["spread_sd_mm"] = spread_per_thickness * state["geometry"]["foam_thickness_mm"]


def viscoelastic_hysteresis(state, rng, relaxation_strength=None, relaxation_time_s=None,
                            frequency_range_hz=(1.0, 12.0)):
    """The loading/unloading difference from the foam and fabric's viscoelasticity instead of a
    fed-in fraction: the compression that closes the fibre contacts follows the force through a
    standard linear solid (data/physics/textile_contact.py; defaults fitted there to the paper's
    8.3 % over 1-12 Hz). Each press is caught on a haversine load cycle of a frequency drawn in
    `frequency_range_hz`, at a random point of its loading or unloading half; the transducer sees
    the force that the lagging compression corresponds to."""
    strength = FOAM["relaxation_strength"] if relaxation_strength is None else relaxation_strength
    tau = FOAM["relaxation_time_s"] if relaxation_time_s is None else relaxation_time_s
    low, high = frequency_range_hz
    if strength < 0 or not tau > 0 or not 0 < low <= high:
        _fail("viscoelastic_hysteresis", f"needs relaxation_strength >= 0, relaxation_time_s > 0 and "
                                         f"0 < frequency low <= high, got {strength}, {tau}, {list(frequency_range_hz)}")
    n = len(state["patch_force_n"])
    factor = lag_factor(rng.uniform(low, high, n), rng.random(n) < 0.5, rng.uniform(0.2, 1.0, n), strength, tau)
    state["patch_force_n"] = state["patch_force_n"] * factor[:, None]


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


def textile_contact(state, initial_slope_per_n=None, saturated_fraction=None, crossing_shape=None):
    """The transducer from fibre-contact physics (data/physics/textile_contact.py
    `normalised_resistance`): Holm constriction spots at the fibre crossings, their number set
    by a Weibull distribution of closure forces (Greenwood-Williamson counting), in parallel with
    the base fabric. Defaults (textile_contact.CONTACT): the paper's slope over the early 10 N and
    9.9 % saturation, the Weibull shape fitted there so the curve stays straight to 10 N."""
    params = {"initial_slope_per_n": initial_slope_per_n, "saturated_fraction": saturated_fraction,
              "crossing_shape": crossing_shape}
    params = {k: CONTACT[k] if v is None else v for k, v in params.items()}
    if not 0 < params["initial_slope_per_n"] < (1 - params["saturated_fraction"]) / 10.0 \
            or not 0 < params["saturated_fraction"] < 1 or params["crossing_shape"] < 1:
        _fail("textile_contact", f"needs 0 < saturated_fraction < 1, 0 < initial_slope_per_n < (1 - saturated_fraction) "
                                 f"/ 10 N and crossing_shape >= 1, got {params}")
    force = state["patch_force_n"] * state["patch_sensitivity_scale"][None, :]
    state["patch_conductance_factor"] = 1.0 / normalised_resistance(force, **params)


# -- reading effects --------------------------------------------------------------------------
def _walk(rng, n, width, fraction_per_50_presses, recording, restoring_presses=None):
    """(n, width) drifts of the readings from their recording's unloaded frame, taken just before the
    recording's first press (restarting per recording). `restoring_presses` None: a random walk
    whose change over 50 presses has sd `fraction_per_50_presses`, so it grows without bound as
    sqrt(presses). A number tau: the material springs back (an Ornstein-Uhlenbeck process,
    correlation time tau presses) with the same sd of the change over 50 presses, so the drift from
    the unloaded frame stays bounded at sd fraction / sqrt(1 - exp(-50 / tau))."""
    recording = np.asarray(recording if recording is not None else np.zeros(n, dtype=int))
    starts = np.flatnonzero(np.r_[True, recording[1:] != recording[:-1]])
    if restoring_presses is None:
        steps = rng.normal(0.0, fraction_per_50_presses / np.sqrt(50.0), (n, width))
        walk = np.cumsum(steps, axis=0)
        return walk - np.repeat(walk[starts] - steps[starts], np.diff(np.r_[starts, n]), axis=0)
    keep = np.exp(-1.0 / restoring_presses)
    level = fraction_per_50_presses / np.sqrt(2.0 * (1.0 - keep ** 50))     # stationary sd
    state = np.empty((n + 1, width))                                        # state[k]: before press k
    state[0] = rng.normal(0.0, level, width)
    kicks = rng.normal(0.0, level * np.sqrt(1.0 - keep ** 2), (n, width))
    for k in range(n):
        state[k + 1] = keep * state[k] + kicks[k]
    return state[1:] - np.repeat(state[starts], np.diff(np.r_[starts, n]), axis=0)


def _restoring_ok(restoring_presses) -> bool:
    return restoring_presses is None or restoring_presses > 0


def electrode_contact_impedance(state, rng, resistance_ohm=1000.0, spread=0.3, drift_fraction_per_50_presses=0.05,
                                restoring_presses=None):
    """Each stitched electrode meets the base fabric through a contact resistance in series
    (conductive thread through the fabric, silver paste on the point electrodes, seed 002 §3.3).
    For a point electrode the complete electrode model (Somersalo, Cheney & Isaacson, SIAM J.
    Appl. Math. 52, 1992) reduces to that series resistance: a reading on an electrode that
    carries the injected current includes I z_e, the others none. A constant z_e cancels in the
    change from the unloaded frame; its drift does not. z_e is lognormal over electrodes
    (`spread`) about `resistance_ohm`, and drifts with sd `drift_fraction_per_50_presses` of z_e
    after 50 presses, restarting per recording: a random walk, or bounded when
    `restoring_presses` is set (`_walk`). The paper gives no contact resistance; the numbers are
    our choice (swept in docs/ert.md)."""
    if resistance_ohm < 0 or spread < 0 or drift_fraction_per_50_presses < 0 or not _restoring_ok(restoring_presses):
        _fail("electrode_contact_impedance", f"needs resistance_ohm, spread, drift_fraction_per_50_presses >= 0 and "
                                             f"restoring_presses > 0 or null, got {resistance_ohm}, {spread}, "
                                             f"{drift_fraction_per_50_presses}, {restoring_presses}")
    injections, measurements = state["patterns"]
    n_electrodes = int(max(injections.max(), measurements.max())) + 1
    z0 = resistance_ohm * np.exp(rng.normal(0.0, spread, n_electrodes))
    n = len(state["voltage_v"])
    dz = z0 * _walk(rng, n, n_electrodes, drift_fraction_per_50_presses, state.get("recording"), restoring_presses)
    # channel (a, b; c, d) reads I (z_a [c = a] - z_b [c = b] - z_a [d = a] + z_b [d = b])
    a, b = injections[:, 0:1], injections[:, 1:2]
    c, d = measurements[None, :, 0], measurements[None, :, 1]
    weight = np.zeros((len(injections) * len(measurements), n_electrodes))
    rows = np.arange(weight.shape[0]).reshape(len(injections), len(measurements))
    for electrode, sign in ((a, 1.0), (b, -1.0)):
        e = np.broadcast_to(electrode, rows.shape)
        np.add.at(weight, (rows, e), sign * ((c == e).astype(float) - (d == e).astype(float)))
    state["voltage_v"] = state["voltage_v"] + state["current_a"] * dz @ weight.T


def baseline_drift(state, rng, fraction_per_50_presses=0.0057, restoring_presses=None):
    """The fabric's unloaded resistance wanders: 0.57 % of its initial value over 50 cycles
    (seed 002 §3.2). Each patch's base conductance takes a random walk over the press order
    whose sd after 50 presses is that fraction; the voltages move by J_patch delta (the
    linearised forward model, eq. 3; the walk is far too small for the nonlinearity to matter).
    The baseline frame is taken before each recording's first press, so the drift is not removed
    within a recording; it restarts with each new recording (state["recording"]).
    `restoring_presses` (None: a random walk, unbounded) makes the fabric spring back towards its
    rest state with that correlation time in presses, so the drift stays bounded near the
    measured 0.57 %: the paper ascribes its low shift to "the high resilience of the two
    conductive fabrics, which causes fast restoration" (§6); how fast it does not say."""
    if fraction_per_50_presses < 0 or not _restoring_ok(restoring_presses):
        _fail("baseline_drift", f"needs fraction_per_50_presses >= 0 and restoring_presses > 0 or null, got "
                                f"{fraction_per_50_presses}, {restoring_presses}")
    jacobian = state["patch_jacobian"]()                      # (n_channels, n_patches)
    walk = _walk(rng, len(state["voltage_v"]), jacobian.shape[1], fraction_per_50_presses, state.get("recording"),
                 restoring_presses)
    state["voltage_v"] += walk @ jacobian.T


def adc_noise(state, rng, noise_v=2.0e-4, bits=24, full_scale_v=10.0):
    """White noise on every voltage (the analogue front end and multiplexer settling at 333 kHz),
    then a `bits`-bit ADC over +-full_scale_v (seed 002 §3.4: 24-bit), applied to every frame
    including the unloaded baseline frame."""
    if noise_v < 0 or bits < 1 or full_scale_v <= 0:
        _fail("adc_noise", f"needs noise_v >= 0, bits >= 1, full_scale_v > 0, got {noise_v}, {bits}, {full_scale_v}")
    lsb = 2.0 * full_scale_v / 2 ** bits
    for key in ("voltage_v", "baseline_v"):
        # in place: the same numbers (a + b = b + a, rint = round to 0 decimals) without four
        # temporary copies of every frame (13 M readings at 2000 presses)
        noisy = rng.normal(0.0, noise_v, state[key].shape)
        noisy += state[key]
        noisy /= lsb
        np.rint(noisy, out=noisy)
        noisy *= lsb
        state[key] = np.clip(noisy, -full_scale_v, full_scale_v, out=noisy)


SENSOR_EFFECTS = {"specimen_variation": specimen_variation, "electrode_position_error": electrode_position_error,
                  "fabric_anisotropy": fabric_anisotropy}
PRESS_EFFECTS = {"local_contact": local_contact, "foam_spread": foam_spread, "hysteresis": hysteresis,
                 "viscoelastic_hysteresis": viscoelastic_hysteresis, "contact_resistance": contact_resistance,
                 "textile_contact": textile_contact}
READING_EFFECTS = {"electrode_contact_impedance": electrode_contact_impedance, "baseline_drift": baseline_drift,
                   "adc_noise": adc_noise}
EFFECTS = {**SENSOR_EFFECTS, **PRESS_EFFECTS, **READING_EFFECTS}
RANDOM_EFFECTS = {"specimen_variation", "electrode_position_error", "hysteresis", "viscoelastic_hysteresis",
                  "electrode_contact_impedance", "baseline_drift", "adc_noise"}
