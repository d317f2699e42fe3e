"""Physical and acquisition effects of the rubber12 sheet. A scene runs only those it lists.

Field effects act on one chunk of presses before the current-flow solve, on per-node fields
of shape (n_presses, n_nodes); they are deterministic functions of the press (randomness
belongs to the acquisition). Reading effects act after the solve on the whole data set's
(n_presses, n_channels) readings and draw from their own random generator `rng`. Every
parameter is a keyword with its unit in its name.
"""
import numpy as np

from common.errors import InputError
from data.physics.contact_mechanics import (
    bonded_layer_deflection_mm,
    flat_punch_force_n,
    mean_pressure_pa,
    standard_linear_solid_relaxation,
)
from data.physics.hyperelastic_compression import neo_hookean_stiffening
from data.preprocessing.minmax_scaling import MinMaxScaling


def _needs(state, key, effect, provider):
    if key not in state:
        raise InputError(f"scene rubber12: effect '{effect}' needs '{provider}' listed too")
    return state[key]


# -- field effects --------------------------------------------------------------------------
def specimen(state, rng, thickness_rms_mm=0.1, n_modes=2):
    """The real specimen is not a perfect 6 mm slab: a per-sensor thickness map of the gel.

    A cast gel's thickness varies by a few per cent (the lab checked "approximately 6 mm" with
    a caliper); the CNC indents by a nominal depth measured from one zero set at the sheet's
    centre, so where the gel is thicker the probe goes deeper into it and where it is thinner,
    less (the zero-point error of indentation testing: Oliver & Pharr, J. Mater. Res. 7 (1992)
    1564, sec. on initial penetration). The map is smooth: cosine modes cos(k pi x/L) cos(l pi y/L),
    0 <= k, l <= n_modes, (k, l) != (0, 0), with normal coefficients scaled to `thickness_rms_mm`
    rms over the sheet; drawn once per sensor from this effect's own generator (the same draws
    in every chunk). Sets `thickness_mm` and `indentation_mm` per press, which `contact` uses.
    """
    if thickness_rms_mm < 0 or n_modes < 1:
        raise InputError(f"scene rubber12: specimen needs thickness_rms_mm >= 0 and n_modes >= 1, "
                         f"got {thickness_rms_mm} and {n_modes}")
    geometry = state["geometry"]
    side, h = geometry["side_mm"], geometry["gel_thickness_mm"]
    k, l = np.meshgrid(np.arange(n_modes + 1), np.arange(n_modes + 1), indexing="ij")
    k, l = k.ravel()[1:], l.ravel()[1:]
    coefficient = rng.standard_normal(len(k))
    # rms over the sheet of sum c_kl cos cos: each mode's mean square is 1/4, 1/2 when k or l is 0
    mean_square = np.where((k == 0) | (l == 0), 0.5, 0.25)
    coefficient *= thickness_rms_mm / np.sqrt(np.sum(coefficient**2 * mean_square))

    def deviation(x, y):
        modes = np.cos(np.pi * np.outer(x, k) / side) * np.cos(np.pi * np.outer(y, l) / side)
        return modes @ coefficient

    offset = deviation(state["x_mm"], state["y_mm"]) - deviation(np.array([side / 2]), np.array([side / 2]))
    state["thickness_mm"] = h + deviation(state["x_mm"], state["y_mm"])
    state["indentation_mm"] = np.maximum(state["depth_mm"] + offset, 0.0)


def contact(state, youngs_modulus_pa=1.0e5, poisson_ratio=0.5, thin_layer_correction=True,
            film_modulus_pa=2.0e6, cutoff_strain=1.0e-4):
    """Flat-punch load on the gel, and the strain it puts into the conductive film on top.

    Load: force_n = 2 a E* d (x the thin-layer factor) and pressure_pa = F / (pi a^2): see
    data/physics/contact_mechanics.py for the laws and their sources (d and h from `specimen`
    when it is listed). The other force effects (gel_edges, large_strain, relaxation) scale it.

    Film: the 0.23 mm film is bonded to the gel and follows its surface, which for a gel bonded
    to a rigid base (Burmister's layer, `bonded_layer_deflection_mm`) sinks by d under the punch
    and settles within about the gel's thickness around it. The film is rubber, so
    incompressible (nu = 0.5): its filler volume fraction never changes; what changes is its
    shape. Around the probe the tilted surface stretches it radially by the arc-length strain
    sqrt(1 + w'^2) - 1 (w' taken over one grid cell, the length each node stands for), while the
    surface of an incompressible body under a normal load does not move sideways (Johnson 1985
    eq. 3.22b: u_r ~ (1 - 2 nu) = 0), so the hoop strain is 0. Under the probe the contact
    pressure squeezes the film through its thickness by p / E_film and, volume conserved, it
    spreads in-plane by half that each way. `film_stretch` is the mean in-plane strain, and
    `film_area_strain` the in-plane area change (the film thins by as much). Below
    `cutoff_strain` the film counts as unstrained, which keeps each press's patch of changed
    conductance finite for the patch solver.
    """
    geometry = state["geometry"]
    a, h = geometry["probe_radius_mm"], geometry["gel_thickness_mm"]
    if film_modulus_pa <= 0 or cutoff_strain < 0:
        raise InputError(f"scene rubber12: contact needs film_modulus_pa > 0 and cutoff_strain >= 0, "
                         f"got {film_modulus_pa} and {cutoff_strain}")
    depth = state.get("indentation_mm", state["depth_mm"])
    thickness = state.get("thickness_mm", h)
    state["force_n"] = flat_punch_force_n(depth, a, youngs_modulus_pa, poisson_ratio,
                                          thickness_mm=thickness if thin_layer_correction else None)
    state["pressure_pa"] = mean_pressure_pa(state["force_n"], a)

    nodes = state["node_xy_mm"]
    distance = np.hypot(nodes[None, :, 0] - state["x_mm"][:, None], nodes[None, :, 1] - state["y_mm"][:, None])
    half_cell = 0.5 * geometry["spacing_mm"]
    # The profile is linear in d: tilt it once for d = 1 and scale.
    inner = np.maximum(distance - half_cell, a)
    outer = np.maximum(distance + half_cell, a)
    rise = (bonded_layer_deflection_mm(inner, 1.0, a, h) - bonded_layer_deflection_mm(outer, 1.0, a, h))
    slope = depth[:, None] * rise / (outer - inner + 1e-12)
    radial = np.sqrt(1.0 + slope**2) - 1.0
    squeezed = state["pressure_pa"][:, None] / film_modulus_pa * (distance <= a)
    area = np.where(distance <= a, squeezed, radial)
    stretch = 0.5 * area
    stretch[stretch < cutoff_strain] = 0.0
    area[stretch == 0.0] = 0.0
    state["film_stretch"], state["film_area_strain"] = stretch, area


def gel_edges(state):
    """The gel has free edges, so its stiffness under the probe depends on where it presses.

    First step of Hetényi's method for a body bounded by a free face (J. Appl. Mech. 37 (1970)
    70-76, the quarter-space): superpose the load's mirror image in each free face. The punch
    then sinks by its own deflection plus that of its images in the four sides (and the four
    double images at the corners) at their distances, from the same bonded-layer profile; the
    force for a given depth scales by the inverse. For a 6 mm gel its profile is gone within
    ~3 h, so at the lab's press points (>= 9 mm from the edges) this is small: +1.2 % at the
    corners P1/P3/P7/P9, +0.6 % at the edge midpoints, +0.1 % at P5 (stiffer, because the
    images' surfaces bulge up there); +20 % at (5, 5) mm. The sign is this approximation's: it
    leaves out the side face's own bulging, which would soften the gel near an edge, so the
    effect is not in the default list (docs/rubber12.md).
    """
    force = _needs(state, "force_n", "gel_edges", "contact")
    geometry = state["geometry"]
    a, h, side = geometry["probe_radius_mm"], geometry["gel_thickness_mm"], geometry["side_mm"]
    x, y = state["x_mm"], state["y_mm"]
    # images: the press mirrored in x = 0, x = side, y = 0, y = side, and in two sides at once
    mirrored_x, mirrored_y = (x, -x, 2 * side - x), (y, -y, 2 * side - y)
    distance = np.stack([np.hypot(ix - x, iy - y) for i, ix in enumerate(mirrored_x)
                         for j, iy in enumerate(mirrored_y) if (i, j) != (0, 0)], axis=1)
    extra = bonded_layer_deflection_mm(distance, 1.0, a, h).sum(axis=1)
    factor = 1.0 / (1.0 + extra)
    state["force_n"] = force * factor
    state["pressure_pa"] = state["pressure_pa"] * factor


def large_strain(state):
    """Rubber stiffens at large strain: linear elasticity holds to ~15 % (physics notes), the lab
    pressed to 50 % of the gel. The gel under the probe is taken as a neo-Hookean column at the
    mean strain d/h, whose secant stiffness over the small-strain one (Treloar 1975,
    `neo_hookean_stiffening`) scales the force: x1.05 at 0.3 mm, x2.3 at 3 mm."""
    force = _needs(state, "force_n", "large_strain", "contact")
    h = state.get("thickness_mm", state["geometry"]["gel_thickness_mm"])
    factor = neo_hookean_stiffening(state.get("indentation_mm", state["depth_mm"]) / h)
    state["force_n"] = force * factor
    state["pressure_pa"] = state["pressure_pa"] * factor


def relaxation(state, relaxed_fraction=0.25, time_constant_s=1.5, hold_s=5.0, window_s=0.5,
               step_mm=0.3, first_depth_mm=0.3):
    """The gel relaxes during each 5 s hold, so the load cell reads less than the instant load.

    Quasi-linear viscoelasticity (Fung, *Biomechanics*, 2nd ed. 1993, sec. 7.6): the force is
    the sum of each depth increment's elastic force times the relaxation function G(t)/G(0) of a
    standard linear solid (`standard_linear_solid_relaxation`) since that increment. The lab
    stepped the depth up from `first_depth_mm` by `step_mm` with a `hold_s` hold at each level
    and read the mean of the last `window_s`; a press at depth d therefore carries the history
    first_depth, first_depth + step, ..., d (taken as a loading history for unloading presses
    too). relaxed_fraction 0.25 and tau 1.5 s are estimates for a soft silicone gel (marked as
    such: the paper gives neither), with the elastic force taken linear in the increments.
    """
    force = _needs(state, "force_n", "relaxation", "contact")
    if not 0.0 <= relaxed_fraction < 1.0 or time_constant_s <= 0 or not 0 < window_s <= hold_s or step_mm <= 0:
        raise InputError("scene rubber12: relaxation needs 0 <= relaxed_fraction < 1, time_constant_s > 0, "
                         f"0 < window_s <= hold_s and step_mm > 0, got {relaxed_fraction}, {time_constant_s}, "
                         f"{window_s}, {hold_s}, {step_mm}")
    depth = state.get("indentation_mm", state["depth_mm"])
    steps = np.maximum(np.floor((state["depth_mm"] - first_depth_mm) / step_mm + 1e-9), 0.0)  # increments after the first
    # read at hold_s - window_s / 2 after the last increment, on average over the window
    window = np.linspace(hold_s - window_s, hold_s, 11)

    def mean_relaxation(age_s):
        return standard_linear_solid_relaxation(age_s[..., None] + window, relaxed_fraction, time_constant_s).mean(-1)

    most = int(steps.max()) if steps.size else 0
    age = np.arange(most + 1)[None, :] * hold_s                       # increments, newest first
    weight = mean_relaxation(age)                                       # (1, most + 1)
    newest = np.arange(most + 1)[None, :] < steps[:, None]             # the step_mm increments
    first = np.arange(most + 1)[None, :] == steps[:, None]             # the first press, oldest
    increment = np.where(newest, step_mm, 0.0) + np.where(first, depth[:, None] - steps[:, None] * step_mm, 0.0)
    ratio = (increment * weight).sum(axis=1) / np.maximum(depth, 1e-12)
    state["force_n"] = force * ratio
    state["pressure_pa"] = state["pressure_pa"] * ratio


def hysteresis(state, loss_fraction=0.10):
    """Loading and unloading paths differ: on the way back the rubber keeps more strain.

    Carbon-black elastomers and FSR-like films show about +10 % hysteresis (physics notes).
    A press reached from a deeper press at the same point (protocol sequence `up_down`)
    carries (1 + loss_fraction) times the film strain of the same press on the way up.
    """
    stretch = _needs(state, "film_stretch", "hysteresis", "contact")
    factor = 1.0 + loss_fraction * state["unloading"][:, None]
    state["film_stretch"] = stretch * factor
    state["film_area_strain"] = state["film_area_strain"] * factor


def cycle_response(state, rng, gain_sd=0.0):
    """The film's response amplitude differs from one indentation cycle to the next.

    Carbon-black rubber's conducting network is partly broken by each stretch and recovers
    slowly (the electrical Mullins effect: Mullins, Rubber Chem. Technol. 21 (1948) 281), so
    two indentations of the same point do not strain the network alike. The film strain of
    every press of a cycle (a lab point's depth sweep; a random-protocol press on its own) is
    scaled by one draw of 1 + gain_sd * N(0, 1). No source gives its size for this film; the
    config sizes gain_sd to the paper's own repeatability, "a coefficient of variation below
    2.3 % across all channels" (§II-E), not to the Table II it is judged by.
    """
    stretch = _needs(state, "film_stretch", "cycle_response", "contact")
    if gain_sd < 0:
        raise InputError(f"scene rubber12: cycle_response needs gain_sd >= 0, got {gain_sd}")
    cycle = state["cycle"]
    # one draw per cycle, indexed by the cycle's number: every chunk redraws the same sequence
    scale = 1.0 + gain_sd * rng.standard_normal(int(cycle.max()) + 1 if cycle.size else 0)[cycle]
    state["film_stretch"] = stretch * scale[:, None]
    state["film_area_strain"] = state["film_area_strain"] * scale[:, None]


def percolation(state, filler_fraction=0.045, percolation_threshold=0.040, exponent=2.0,
                junction_loss_per_strain=1.0, floor=1.0e-3):
    """Percolation scaling of conductivity as stretching breaks conducting junctions.

    sigma / sigma_0 = ((p - p_c) / (p_0 - p_c))^t (Balberg, PRL 59, 1987; t ~ 1.3 in 2-D,
    2 in 3-D, 2-6 for carbon black). The rubber is incompressible, so the filler volume
    fraction p_0 does not change; what stretching does is open the gaps between neighbouring
    aggregates, so a share of the junctions that conducted fall beyond tunnelling reach. That
    share is taken as proportional to the film's mean in-plane stretch: the conducting fraction
    is p = p_0 (1 - junction_loss_per_strain * stretch), an assumption of this model (the form
    of the path-breaking argument of carbon-black strain sensors), amplified near threshold by
    p_0 / (p_0 - p_c). A film stretched past its threshold keeps `floor` of its conductance
    (residual conduction through the matrix), so the sheet never becomes an insulator.
    """
    if not percolation_threshold < filler_fraction < 1.0 or junction_loss_per_strain < 0 or not 0 < floor <= 1:
        raise InputError(f"scene rubber12: percolation needs percolation_threshold < filler_fraction < 1, "
                         f"junction_loss_per_strain >= 0 and 0 < floor <= 1, got {percolation_threshold}, "
                         f"{filler_fraction}, {junction_loss_per_strain}, {floor}")
    stretch = _needs(state, "film_stretch", "percolation", "contact")
    fraction = filler_fraction * (1.0 - junction_loss_per_strain * stretch)
    above = np.maximum((fraction - percolation_threshold) / (filler_fraction - percolation_threshold), 0.0)
    relative = np.maximum(above**exponent, floor)
    state["conductance_scale"] = state.get("conductance_scale", 1.0) * relative


def tunneling(state, barrier_height_ev=0.5, gap_nm=1.5):
    """Tunnelling across the polymer gaps between filler particles, and the film's thinning.

    Junction resistance R ~ s exp(gamma s), gamma = 10.25 nm^-1 sqrt(phi / 1 eV) (Simmons,
    J. Appl. Phys. 34, 1963; Zhang et al., J. Polym. Sci. B 38, 2000). The matrix deforms
    affinely, so a gap of direction n opens by s0 (n . eps . n) (Hu et al., Acta Mater. 56 (2008)
    2929). In-plane current along u crosses junctions weighted by (n . u)^2; averaged over
    random orientations that is <(n.u)^2 n.eps.n> / <(n.u)^2> = (tr eps + 2 eps_uu) / 5, and
    with tr eps = 0 (incompressible), averaged over in-plane u: (2/5) of the mean in-plane
    strain. Through-thickness squeeze therefore closes the gaps across the film while the
    in-plane stretch that comes with it opens those along the current, and the latter wins.
    The junctions give R / R0 = (1 + e) exp(gamma s0 e), e = (2/5) stretch; the sheet
    conductance also scales with the film's thickness, t / t0 = 1 / (1 + area strain).
    """
    stretch = _needs(state, "film_stretch", "tunneling", "contact")
    gamma_per_nm = 10.25 * np.sqrt(barrier_height_ev)
    gap_strain = 0.4 * stretch
    ratio = (1.0 + gap_strain) * np.exp(gamma_per_nm * gap_nm * gap_strain) * (1.0 + state["film_area_strain"])
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


def load_cell(state, rng, noise_n=0.05, samples_averaged=50, resolution_n=0.01):
    """The load cell that measured force: Gaussian noise of `noise_n` per sample, averaged over
    the same `samples_averaged` samples as the channels, read to `resolution_n` (quantisation).
    Values are estimates for a small strain-gauge load cell with a 24-bit bridge ADC (the paper
    names neither). The reported pressure is the measured force over the probe area; a reading
    below zero (noise when the probe misses the gel) is reported as zero."""
    if noise_n < 0 or samples_averaged < 1 or resolution_n < 0:
        raise InputError(f"scene rubber12: load_cell needs noise_n >= 0, samples_averaged >= 1 and "
                         f"resolution_n >= 0, got {noise_n}, {samples_averaged}, {resolution_n}")
    force = state["force_n"]
    measured = force + rng.normal(0.0, noise_n / np.sqrt(samples_averaged), size=force.shape)
    if resolution_n > 0:
        measured = resolution_n * np.rint(measured / resolution_n)
    # A press that misses a thin spot of the gel loads nothing: its reading is the cell's noise
    # around zero, and a contact force or pressure below zero is not a reading of a press.
    measured = np.maximum(measured, 0.0)
    state["pressure_pa"] = mean_pressure_pa(measured, state["probe_radius_mm"])
    state["force_n"] = measured


def minmax_normalize(state, rng):
    """Min-max normalisation of each channel over the data set, as the lab did: readings become
    unitless in [0, 1] (channel names change from r_XX_ohm to r_XX_norm). A channel that never
    changes maps to 0. The per-channel minimum and span are kept (`state["normalisation"]`, then
    the SensorTable's `normalisation`): a model trained on these channels applies them to raw
    ohms when deployed (data/preprocessing/minmax_scaling.py)."""
    scaling = MinMaxScaling.fit(state["resistance_ohm"], state["channels"])
    state["resistance_ohm"] = scaling.normalise(state["resistance_ohm"])
    state["channels"] = [name.removesuffix("_ohm") + "_norm" for name in state["channels"]]
    state["normalisation"] = scaling


FIELD_EFFECTS = {"specimen": specimen, "contact": contact, "gel_edges": gel_edges, "large_strain": large_strain,
                 "relaxation": relaxation, "hysteresis": hysteresis, "cycle_response": cycle_response,
                 "percolation": percolation,
                 "tunneling": tunneling}
# Field effects that differ from one indentation cycle to the next: part of the repeat variation,
# not of the noise-free response (runs/fidelity/rubber12.py leaves them out of its noise-free curves).
PER_CYCLE_EFFECTS = ("cycle_response",)
READING_EFFECTS = {"electrode_contact": electrode_contact, "temperature_drift": temperature_drift,
                   "adc": adc, "outlier_rejection": outlier_rejection, "load_cell": load_cell,
                   "minmax_normalize": minmax_normalize}
EFFECTS = {**FIELD_EFFECTS, **READING_EFFECTS}
