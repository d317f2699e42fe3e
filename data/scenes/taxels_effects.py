"""Physical and acquisition effects of the taxel array under an elastic cover. Only listed ones run.

The chain (the registry order below):
  load effects    how the surface load reaches the cover: `needle` (a round contact instead of a
                  point), `plate_averaging` (a taxel senses over its plate, not at a point),
                  `hair`, `bump`, `ridge` (what stands on the cover: at most one of these);
  cover effects   the strain at the taxels: `flat` (semi-infinite cover, seed 004 eq. 1) or
                  `finite_layer` (a cover of finite thickness on the rigid chip, bonded or frictionless);
  reading effects `amplifier`, `noise`, `adc`: the acquisition chain (seed 004 Table 1).
Load and cover effects are deterministic functions of the loads and act on a chunk of samples;
reading effects act on the whole set of bridge voltages and draw from their own generator `rng`.

Loads are carried as "nodes": arrays of shape (n_samples, n_nodes) of positions (m) and force
components (N, normal pressing, shear along +x / +y) that sum to each sample's load. Strains
follow the seed's convention: gamma_x, gamma_y, eps_z at the taxel, eps_z negative (compressive)
under a pressing load, gamma_x = -eps_xz (tensor shear, z into the cover), so that seed eq. (1)
holds literally at nu = 0.5.
"""
import numpy as np

from common.errors import InputError
from data.physics.bonded_layer import base_field
from data.physics.elastic_half_space import disc_quadrature, point_load_strain


def _shear_modulus_pa(geometry):
    return geometry["youngs_modulus_pa"] / (2.0 * (1.0 + geometry["poisson_ratio"]))


def _replace_nodes(state, captured, base_x, base_y, normal, shear_x, shear_y):
    """Swap every node for k sub-nodes: captured nodes take the given (n, m, k) base nodes, the
    others are copied k times with 1/k of their load (so arrays stay rectangular)."""
    k = base_x.shape[-1]
    keep = ~captured[..., None]
    share = 1.0 / k
    x = np.where(keep, state["load_x_m"][..., None], base_x)
    y = np.where(keep, state["load_y_m"][..., None], base_y)
    p = np.where(keep, share * state["normal_n"][..., None], normal)
    qx = np.where(keep, share * state["shear_x_n"][..., None], shear_x)
    qy = np.where(keep, share * state["shear_y_n"][..., None], shear_y)
    n = x.shape[0]
    for key, value in (("load_x_m", x), ("load_y_m", y), ("normal_n", p), ("shear_x_n", qx), ("shear_y_n", qy)):
        state[key] = value.reshape(n, -1)


def _only_one(state, name, group):
    taken = state.setdefault(f"_{group}", name)
    if taken != name:
        raise InputError(f"scene taxels: effects '{taken}' and '{name}' both model the cover's "
                         f"{group}; list only one of them")


# -- load effects -----------------------------------------------------------------------------
def needle(state, diameter_um=100.0, rings=1, points_per_ring=8):
    """A round needle tip instead of a point: the load spread uniformly over a disc of the tip's
    diameter (seed 004 Table 1: 100 um, round), by superposing point loads at the nodes of an
    equal-area ring quadrature (data/physics/elastic_half_space.py, Johnson 1985 sec. 3.4)."""
    if not diameter_um > 0 or rings < 1 or points_per_ring < 1:
        raise InputError(f"scene taxels: needle needs diameter_um > 0 and rings, points_per_ring >= 1, "
                         f"got {diameter_um}, {rings}, {points_per_ring}")
    nx, ny, weights = disc_quadrature(0.5e-6 * diameter_um, rings, points_per_ring)
    for key in ("load_x_m", "load_y_m", "normal_n", "shear_x_n", "shear_y_n"):
        state[key] = np.repeat(state[key], nx.size, axis=1)
    reps = state["load_x_m"].shape[1] // nx.size
    state["load_x_m"] = state["load_x_m"] + np.tile(nx, reps)
    state["load_y_m"] = state["load_y_m"] + np.tile(ny, reps)
    w = np.tile(weights, reps)
    for key in ("normal_n", "shear_x_n", "shear_y_n"):
        state[key] = state[key] * w


def plate_averaging(state, points_per_side=2, side_um=None, pressure_moment=False):
    """A taxel's bridges sit around a plate, not at one point: the strain is averaged over a
    square of side `side_um` (default: the plate, `plate_side_um`) by Gauss-Legendre quadrature
    (points_per_side^2 points). The plate and its four bridges form one suspended membrane over
    the etched cavity (seed 004 sec. 2, Fig. 1), and the rubber coats and infiltrates all of it,
    so `side_um` may be the whole membrane's: the length besides the cover thickness that the real
    geometry adds (seed 004 sec. 5 puts the narrower, flatter measured profiles down to the real
    geometry). The area that turns strain into force for the bridge constants stays the plate's.

    pressure_moment: the membrane is one stiff body on its four bridges, whose piezoresistors sit
    at the suspension points, half a side from the centre (seed 004 Fig. 1). Rigid-body statics
    on four equal supports (the same statics as `bump`): the sum of the bridges reads the
    resultant normal load, and each difference (left - right, down - up) reads the moment that
    tilts the membrane about its centre. The shear traction tilts it through the die's force arm
    (seed 004 sec. 7: a hair "elongates the force arm"); the normal load tilts it through its
    own offset, the first moment of the pressure over the membrane. Off-centre pressure therefore
    enters the shear reading. With the scene's read-out (the die's shear and normal force
    sensitivities equal, `TaxelsScene.bridge_constants`) the force arm equals the supports'
    offset s = side / 2, and the pressure E eps_z turns into the equivalent shear strain
        gamma_x += -(E / (2 G s)) <x eps_z> = -((1 + nu) / s) <x eps_z>   (y likewise),
    <.> the average over the membrane, x from its centre. Near the load the pressure's moment
    opposes the traction's (the rubber is pushed away from the load, the pressure is highest on
    the side towards it), which lowers the shear sensitivity of a normal scan (fidelity row 4;
    docs/taxels.md). No parameter besides the membrane's side enters."""
    side = state["geometry"]["plate_side_um"] if side_um is None else side_um
    if points_per_side < 1 or not (np.isfinite(side) and side > 0):
        raise InputError(f"scene taxels: plate_averaging needs points_per_side >= 1 and side_um > 0, "
                         f"got {points_per_side}, {side_um}")
    if not isinstance(pressure_moment, bool):
        raise InputError(f"scene taxels: plate_averaging.pressure_moment must be true or false, got {pressure_moment!r}")
    nodes, weights = np.polynomial.legendre.leggauss(int(points_per_side))
    half = 0.5e-6 * side
    gx, gy = np.meshgrid(nodes * half, nodes * half)
    state["sensing_offsets_m"] = np.column_stack([gx.ravel(), gy.ravel()])
    state["sensing_weights"] = np.outer(weights, weights).ravel() / 4.0
    if pressure_moment:
        state["tilt_lever_m"] = half


def hair(state, length_um=1000.0, capture_radius_um=250.0, boss_height_um=100.0):
    """A rigid rod on each taxel's plate, standing through the cover (seed 004 sec. 7).

    Statics of a rigid lever: a load touching the rod (within `capture_radius_um` of the taxel's
    centre) goes straight to the plate instead of through the rubber; its normal part presses the
    plate, its shear part acts at the rod's length instead of at the plate's own boss, so the
    plate's shear reading grows by the force-arm ratio length_um / boss_height_um ("it elongates
    the force arm"). Plate forces are expressed as the cover strain that would load the plate the
    same way: eps_z = -F_z / (E A), gamma = F_t / (2 G A), A the plate's area.
    """
    _only_one(state, "hair", "surface")
    if not (length_um > 0 and capture_radius_um > 0 and boss_height_um > 0):
        raise InputError("scene taxels: hair needs length_um, capture_radius_um, boss_height_um > 0")
    taxels = state["taxel_xy_m"]
    dx = state["load_x_m"][..., None] - taxels[:, 0]
    dy = state["load_y_m"][..., None] - taxels[:, 1]
    touching = np.hypot(dx, dy) < capture_radius_um * 1e-6                   # (n, m, T)
    geometry = state["geometry"]
    area = (geometry["plate_side_um"] * 1e-6) ** 2
    arm = length_um / boss_height_um
    fz = np.einsum("nmt,nm->nt", touching, state["normal_n"])
    fx = np.einsum("nmt,nm->nt", touching, state["shear_x_n"])
    fy = np.einsum("nmt,nm->nt", touching, state["shear_y_n"])
    shear_modulus = _shear_modulus_pa(geometry)
    direct = np.stack([arm * fx / (2 * shear_modulus * area), arm * fy / (2 * shear_modulus * area),
                       -fz / (geometry["youngs_modulus_pa"] * area)], axis=-1)
    state["direct_strain"] = state.get("direct_strain", 0.0) + direct
    carried = touching.any(axis=-1)
    for key in ("normal_n", "shear_x_n", "shear_y_n"):
        state[key] = np.where(carried, 0.0, state[key])


def _cap_height(offset_fraction, height_um):
    """Surface height above the base of a round cap (bump) or a round-topped ridge, at a
    fraction of its half-width from the centre: a spherical/cylindrical segment, approximated by
    h sqrt(1 - f^2) (exact for a hemisphere or half-cylinder)."""
    return 1e-6 * height_um * np.sqrt(np.clip(1.0 - offset_fraction**2, 0.0, 1.0))


def bump(state, diameter_um=560.0, height_um=265.0, rings=1, points_per_ring=7, probe_diameter_um=0.0):
    """A hemispherical elastic bump moulded above each taxel (seed 004 sec. 8: 250-280 um high,
    360-760 um wide, on a ~200 um layer).

    Model (Saint-Venant / rigid-cap statics, Timoshenko & Goodier 1970 sec. 19): the bump is
    short and stubby, so what reaches the layer below is the statically equivalent load at its
    base: the resultant force and the moment of the loads that touch it, spread over the base
    disc as a uniform plus linear pressure (p = P/A + M.r / I) and a uniform shear. A load
    anywhere on the bump is thereby collected above the taxel ("they integrate the load from
    their entire surface"), and a shear applied at the bump's surface height acts with a moment
    arm that tilts the base: the lateral sensitivity rises (their Fig. 9).

    A broad probe (`probe_diameter_um` > 0, e.g. a fingertip as in their Fig. 9) is rigid next
    to the rubber and rests on the bump tops under it, which stand 250-280 um proud: when its
    footprint covers bump centres, its whole load is shared equally among those bumps (equal,
    parallel springs) and enters each at the bump's top centre; the flat cover between them
    carries nothing ("the highest stress values are around the first contact points", sec. 8).
    With no bump under it, or for a point contact (0), a load is collected only by the bump it
    lands on.
    """
    _only_one(state, "bump", "surface")
    if not (diameter_um > 0 and height_um >= 0 and probe_diameter_um >= 0):
        raise InputError(f"scene taxels: bump needs diameter_um > 0, height_um >= 0 and probe_diameter_um >= 0, "
                         f"got {diameter_um}, {height_um}, {probe_diameter_um}")
    radius = 0.5e-6 * diameter_um
    if diameter_um * 1e-3 >= state["geometry"]["pitch_mm"]:
        raise InputError(f"scene taxels: bump diameter {diameter_um} um must be below the pitch "
                         f"({state['geometry']['pitch_mm']} mm) so bumps do not overlap")
    bx, by, bw = disc_quadrature(radius, rings, points_per_ring)
    second_moment = np.sum(bw * bx * bx)                 # per unit area-weight: I/A about either axis
    taxels = state["taxel_xy_m"]
    dx = state["load_x_m"][..., None] - taxels[:, 0]                          # (n, m, T)
    dy = state["load_y_m"][..., None] - taxels[:, 1]
    distance = np.hypot(dx, dy)
    p, qx, qy = (state[key][..., None] for key in ("normal_n", "shear_x_n", "shear_y_n"))
    # share[n, m, t]: the part of node m's load that bump t carries; arm: where on the bump it acts.
    on_bump = distance < radius            # bumps do not overlap: at most one per node
    share = on_bump.astype(float)
    offset_x, offset_y = dx * on_bump, dy * on_bump
    surface = _cap_height(distance / radius, height_um) * on_bump
    if probe_diameter_um > 0:
        under = distance < 0.5e-6 * probe_diameter_um
        resting = under.any(axis=-1, keepdims=True)
        share = np.where(resting, under / np.maximum(under.sum(axis=-1, keepdims=True), 1), share)
        offset_x = np.where(resting, 0.0, offset_x)    # the probe's share enters at each top centre
        offset_y = np.where(resting, 0.0, offset_y)
        surface = np.where(resting, 1e-6 * height_um * under, surface)
    # Resultant and moment about each bump's base centre, summed over the nodes it carries.
    force = np.einsum("nmt,nm->nt", share, p[..., 0])
    force_x = np.einsum("nmt,nm->nt", share, qx[..., 0])
    force_y = np.einsum("nmt,nm->nt", share, qy[..., 0])
    moment_x = np.einsum("nmt,nmt->nt", share, p * offset_x + qx * surface)   # pressure shifts towards +x
    moment_y = np.einsum("nmt,nmt->nt", share, p * offset_y + qy * surface)
    carried = share.sum(axis=-1)                                               # (n, m), 0 or 1
    n = p.shape[0]
    base_normal = bw * (force[..., None] + (moment_x[..., None] * bx + moment_y[..., None] * by) / second_moment)
    for key, value in (("load_x_m", np.broadcast_to(taxels[:, 0, None] + bx, base_normal.shape)),
                       ("load_y_m", np.broadcast_to(taxels[:, 1, None] + by, base_normal.shape)),
                       ("normal_n", base_normal), ("shear_x_n", force_x[..., None] * bw),
                       ("shear_y_n", force_y[..., None] * bw)):
        rest = state[key] * (1.0 - carried) if key in ("normal_n", "shear_x_n", "shear_y_n") else state[key]
        state[key] = np.concatenate([rest, value.reshape(n, -1)], axis=1)


def ridge(state, width_um=560.0, height_um=265.0, orientation_deg=0.0, points_across=3):
    """Fingerprint-like ridges along `orientation_deg` (0 = along x) through the taxel centres
    (seed 004 sec. 8, Fig. 8 and 10).

    Same rigid-cap statics as `bump`, in the ridge's cross-section only: a load on the ridge is
    moved across to the ridge and spread over its width with the moment of its across-position
    and of its across-shear at the ridge's surface height. Along the ridge nothing is collected:
    the ridge is a continuous wall in that direction, so a load keeps its along-position and a
    shear along the ridge is carried without a moment arm. Motion across the ridge therefore
    meets the collected, tilted response; motion along it sees the flat cover's profile (the
    direction selectivity of their Fig. 10c-d).
    """
    _only_one(state, "ridge", "surface")
    if not (width_um > 0 and height_um >= 0 and points_across >= 1):
        raise InputError(f"scene taxels: ridge needs width_um > 0, height_um >= 0, points_across >= 1, "
                         f"got {width_um}, {height_um}, {points_across}")
    half = 0.5e-6 * width_um
    theta = np.deg2rad(orientation_deg)
    normal_dir = np.array([-np.sin(theta), np.cos(theta)])
    lines = np.unique(np.round(state["taxel_xy_m"] @ normal_dir, 12))     # across-offsets of the ridges
    across = state["load_x_m"] * normal_dir[0] + state["load_y_m"] * normal_dir[1]
    gaps = across[..., None] - lines
    nearest = np.argmin(np.abs(gaps), axis=-1)
    a = np.take_along_axis(gaps, nearest[..., None], axis=-1)[..., 0]
    captured = np.abs(a) < half
    nodes = (np.arange(points_across) + 0.5) / points_across * 2 * half - half
    weights = np.full(points_across, 1.0 / points_across)
    second_moment = np.sum(weights * nodes * nodes)
    p, qx, qy = state["normal_n"], state["shear_x_n"], state["shear_y_n"]
    q_across = qx * normal_dir[0] + qy * normal_dir[1]
    z_s = _cap_height(a / half, height_um)
    moment = p * a + q_across * z_s
    base_x = (state["load_x_m"] - a * normal_dir[0])[..., None] + nodes * normal_dir[0]
    base_y = (state["load_y_m"] - a * normal_dir[1])[..., None] + nodes * normal_dir[1]
    normal = weights * (p[..., None] + moment[..., None] * nodes / max(second_moment, 1e-30))
    # Along the ridge, positions and shear pass unchanged: no along-coordinate appears here.
    _replace_nodes(state, captured, base_x, base_y, normal, weights * qx[..., None], weights * qy[..., None])


# -- cover effects ------------------------------------------------------------------------------
def _sensing_points(state):
    offsets = state.get("sensing_offsets_m", np.zeros((1, 2)))
    weights = state.get("sensing_weights", np.ones(1))
    points = state["taxel_xy_m"][:, None, :] + offsets[None, :, :]         # (T, S, 2)
    return points, weights


def _field_at_taxels(state, field_fn):
    """Sum `field_fn(dx, dy, depth, P, Qx, Qy) -> (gamma_x, gamma_y, eps_z)` over load nodes,
    averaged over sensing points: returns (n, T, 3)."""
    points, weights = _sensing_points(state)
    shape = (slice(None), slice(None), None, None)
    dx = points[None, None, :, :, 0] - state["load_x_m"][shape]              # (n, m, T, S)
    dy = points[None, None, :, :, 1] - state["load_y_m"][shape]
    depth = state["thickness_m"][:, None, None, None]
    gamma_x, gamma_y, eps_z = field_fn(dx, dy, depth, state["normal_n"][shape],
                                       state["shear_x_n"][shape], state["shear_y_n"][shape])
    strain = np.stack([np.einsum("nmts,s->nt", c, weights) for c in (gamma_x, gamma_y, eps_z)], axis=-1)
    if "tilt_lever_m" in state:          # plate_averaging(pressure_moment=True): its docstring
        per_strain = (1.0 + state["geometry"]["poisson_ratio"]) / state["tilt_lever_m"]
        moments = np.einsum("nmts,s,sk->ntk", eps_z, weights, state["sensing_offsets_m"])
        strain[..., :2] -= per_strain * moments
    return strain


def flat(state):
    """Semi-infinite cover (seed 004 eq. 1; for any nu Boussinesq + Cerruti, Johnson 1985 eq.
    3.19-3.20, data/physics/elastic_half_space.py): the strain at the taxel, at a depth equal to
    the cover thickness, as if the rubber went on below the chip."""
    _only_one(state, "flat", "cover")
    geometry = state["geometry"]

    def field(dx, dy, depth, p, qx, qy):
        f = point_load_strain(dx, dy, depth, p, qx, qy, geometry["youngs_modulus_pa"], geometry["poisson_ratio"])
        return -f.eps_xz, -f.eps_yz, f.eps_zz

    state["strain"] = _field_at_taxels(state, field)


INTERFACES = ("bonded", "frictionless")
SENSING = ("traction", "cover_strain")


def finite_layer(state, interface="bonded", sensing="traction", sensing_height_um=0.0):
    """Cover of finite thickness h on the rigid chip (Fourier-Hankel layer solution, Burmister
    1945; Sneddon 1951 ch. 10; data/physics/bonded_layer.py).

    interface: "bonded" (default: the cover is cast on the chip or glued to it with the same
    silicone, seed 004 sec. 2, and it carries the shear loads the taxels measure) or
    "frictionless" (a lubricated rigid base: w = 0, no shear traction; it cannot carry a shear
    load at all, so shear loads are an InputError and the shear readings are zero).
    sensing: "traction" (default): the plate reads the load the cover puts on it (eq. 2 is
    structurally a force read-out, seed 004 sec. 4 and ref. [7]): the base traction, reported in
    the strain units of `flat` by eps_z = sigma_zz / E, gamma = -sigma_iz / (2 G) (exact for the
    shear anywhere, and for eps_z under the load at nu = 0.5); with `plate_averaging` it is the
    plate's force over its area. "cover_strain": the rubber's own strain `sensing_height_um`
    above the chip (seed 004 sec. 3 assumption 3, "the strain in the rubber at the centre of the
    piezoresistors"), to first order in that height: eps_z = eps_zz(h) - d * d eps_zz/dz (h),
    gamma = -eps_xz(h) = -sigma_iz / (2 G). A bonded incompressible face cannot strain (eps = 0
    there), so bonded cover_strain needs sensing_height_um > 0; it must stay well below h.
    """
    _only_one(state, "finite_layer", "cover")
    if interface not in INTERFACES or sensing not in SENSING:
        raise InputError(f"scene taxels: finite_layer interface must be one of {', '.join(INTERFACES)} and sensing "
                         f"one of {', '.join(SENSING)}, got '{interface}', '{sensing}'")
    height_m = 1e-6 * float(sensing_height_um)
    if not (np.isfinite(height_m) and height_m >= 0.0) or (height_m > 0.0 and sensing != "cover_strain"):
        raise InputError(f"scene taxels: finite_layer sensing_height_um must be >= 0 and only with "
                         f"sensing=cover_strain, got {sensing_height_um}")
    if sensing == "cover_strain" and interface == "bonded" and height_m == 0.0:
        raise InputError("scene taxels: a bonded cover does not strain at the chip face; give sensing_height_um > 0")
    if np.any(state["thickness_m"] <= height_m):
        raise InputError(f"scene taxels: finite_layer sensing_height_um {sensing_height_um} must be below the cover thickness")
    geometry = state["geometry"]
    shear_modulus = _shear_modulus_pa(geometry)

    def field(dx, dy, depth, p, qx, qy):
        f = base_field(dx, dy, depth, p, qx, qy, geometry["poisson_ratio"], interface, sensing == "cover_strain")
        gamma_x, gamma_y = -f["sigma_xz"] / (2 * shear_modulus), -f["sigma_yz"] / (2 * shear_modulus)
        if sensing == "traction":
            return gamma_x, gamma_y, f["sigma_zz"] / geometry["youngs_modulus_pa"]
        return gamma_x, gamma_y, (f["eps_zz_2g"] - height_m * f["d_eps_zz_2g_dz"]) / (2 * shear_modulus)

    state["strain"] = _field_at_taxels(state, field)


# -- reading effects ------------------------------------------------------------------------------
def amplifier(state, rng, gain=55.0, output_limit_mv=1500.0):
    """The bridge amplifiers (seed 004 Table 1: gain 50-60, linear, output range 1-1500 mV):
    voltages times `gain`, clipped at +/- `output_limit_mv` (the stage saturates)."""
    if not gain > 0 or not output_limit_mv > 0:
        raise InputError(f"scene taxels: amplifier needs gain > 0 and output_limit_mv > 0, got {gain}, {output_limit_mv}")
    state["bridges_mv"] = np.clip(gain * state["bridges_mv"], -output_limit_mv, output_limit_mv)


def noise(state, rng, rms_mv=2.5):
    """Amplifier noise (seed 004 Table 1: 2-3 mV, "mostly from the amplifier itself"), white,
    one independent draw per channel and scan (30 Hz, no averaging)."""
    if rms_mv < 0:
        raise InputError(f"scene taxels: noise needs rms_mv >= 0, got {rms_mv}")
    state["bridges_mv"] = state["bridges_mv"] + rng.normal(0.0, rms_mv, size=state["bridges_mv"].shape)


def adc(state, rng, bits=12, range_mv=5000.0):
    """The acquisition card (seed 004 Table 1: Advantech PCI-1713, 12 bit): bipolar range
    +/- `range_mv`, rounded to the nearest code and clipped at full scale."""
    if bits < 1 or not range_mv > 0:
        raise InputError(f"scene taxels: adc needs bits >= 1 and range_mv > 0, got {bits}, {range_mv}")
    lsb = 2.0 * range_mv / (2**bits)
    codes = np.clip(np.rint(state["bridges_mv"] / lsb), -(2 ** (bits - 1)), 2 ** (bits - 1) - 1)
    state["bridges_mv"] = codes * lsb


LOAD_EFFECTS = {"needle": needle, "plate_averaging": plate_averaging, "hair": hair, "bump": bump, "ridge": ridge}
COVER_EFFECTS = {"flat": flat, "finite_layer": finite_layer}
READING_EFFECTS = {"amplifier": amplifier, "noise": noise, "adc": adc}
EFFECTS = {**LOAD_EFFECTS, **COVER_EFFECTS, **READING_EFFECTS}
