"""The ERT skin's added physics (issue 28 item 4): the fibre-contact transducer and the foam's
standard linear solid (data/physics/textile_contact.py), and the scene effects local_contact,
fabric_anisotropy, electrode_contact_impedance, textile_contact, viscoelastic_hysteresis."""
import numpy as np
import pytest

from common.errors import InputError
from data.physics import textile_contact as tc
from data.physics.sheet_conduction import SheetGrid, SheetSolver, pair_resistance_ohm
from data.scenes.ert import ERTScene

EDGE = [[50, 100], [50, 0], [100, 50], [0, 50], [0, 0], [100, 100]]


def scene(effects, **overrides):
    params = dict(name="ert_test", electrodes_mm=[[20, 200], [100, 200], [180, 200], [200, 100], [180, 0],
                                                   [100, 0], [20, 0], [0, 100], [65, 135], [135, 65]],
                  grid_nodes=21, injection="adjacent", effects=effects, seed=3)
    params.update(overrides)
    return ERTScene(**params)


# -- the transducer law --------------------------------------------------------------------------
def test_contact_law_starts_at_one_falls_and_saturates_at_the_papers_level():
    force = np.linspace(0.0, 200.0, 2001)
    r = tc.normalised_resistance(force)
    assert r[0] == pytest.approx(1.0)
    assert np.all(np.diff(r[force <= 60.0]) < 0) and np.all(np.diff(r) <= 0)
    assert (tc.normalised_resistance(10.0) - 1.0) / 10.0 == pytest.approx(-0.0696, abs=1e-9)   # secant over 0-10 N
    assert r[-1] == pytest.approx(0.099, abs=1e-4)


def test_no_convex_law_with_the_papers_initial_slope_reaches_saturation_by_10_n():
    # m = 1 (Greenwood-Williamson's exponential case) is convex: with tangent slope -0.0696 at 0 it
    # stays above the tangent line, so the paper's three numbers need the bent (m > 1) law.
    fc = (1 - 0.099) / 0.099 / 0.0696            # tangent slope c_max / F_c = 0.0696, c_max = (1 - r_sat) / r_sat
    force = np.linspace(0.0, 12.9, 200)
    r = tc._ratio(force, 0.099, fc, 1.0)
    assert np.all(r >= 1.0 - 0.0696 * force - 1e-12)
    assert tc._ratio(10.0, 0.099, fc, 1.0) > 0.5


def test_the_stored_fits_are_what_the_fits_give():
    assert tc.fit_crossing_shape() == pytest.approx(tc.CONTACT["crossing_shape"], abs=1e-3)
    assert tc.fit_relaxation_strength() == pytest.approx(tc.FOAM["relaxation_strength"], abs=1e-3)


def test_standard_linear_solid_hysteresis():
    assert tc.hysteresis_fraction(5.0, relaxation_strength=0.0) == pytest.approx(0.0, abs=1e-6)
    values = [tc.hysteresis_fraction(f) for f in tc.FREQUENCIES_HZ]
    assert np.mean(values) == pytest.approx(0.083, abs=1e-3)
    # a stiffer relaxation gives more hysteresis; the compression lags, so unloading reads a
    # higher effective force than loading at the same applied force
    assert tc.hysteresis_fraction(3.0, relaxation_strength=0.4) > tc.hysteresis_fraction(3.0, relaxation_strength=0.2)
    loading = tc.lag_factor(np.array([3.0]), np.array([False]), np.array([0.5]))
    unloading = tc.lag_factor(np.array([3.0]), np.array([True]), np.array([0.5]))
    assert loading[0] < 1.0 < unloading[0]
    assert np.allclose(tc.lag_factor(np.full(4, 3.0), np.array([0, 1, 0, 1], bool), np.full(4, 0.7), 0.0), 1.0)


# -- scene effects -------------------------------------------------------------------------------
def test_local_contact_tells_apart_presses_within_one_patch():
    left, right = [[47.0, 150.0, 8.0]], [[53.0, 150.0, 8.0]]     # 10 mm footprints inside the patch at 40-60, 140-160 mm
    whole = scene({"contact_resistance": {}})
    local = scene({"contact_resistance": {}, "local_contact": {}})
    a, b = whole.simulate(np.array(left)).channels, whole.simulate(np.array(right)).channels
    assert np.allclose(a, b)                                            # the whole patch changes alike
    a, b = local.simulate(np.array(left)).channels, local.simulate(np.array(right)).channels
    assert np.abs(a - b).max() > 0.05 * np.abs(a).max()


def test_fabric_anisotropy_makes_x_and_y_differ_and_mirrors():
    grid = SheetGrid(100.0, 21, np.array(EDGE, dtype=float), 0.0)
    iso = SheetSolver(grid).transfer_resistance(np.ones(21 * 21))
    assert np.allclose(SheetSolver(grid, 1.0).transfer_resistance(np.ones(21 * 21)), iso)
    pairs = np.array([[2, 3], [0, 1]])                       # across x, across y
    r2 = pair_resistance_ohm(SheetSolver(grid, 2.0).transfer_resistance(np.ones(21 * 21)), pairs)
    r_half = pair_resistance_ohm(SheetSolver(grid, 0.5).transfer_resistance(np.ones(21 * 21)), pairs)
    assert r2[0] < r2[1]                                    # conducts better along x
    assert r2[0] == pytest.approx(r_half[1]) and r2[1] == pytest.approx(r_half[0])
    with pytest.raises(InputError):
        SheetSolver(grid, 0.0)


def test_fabric_anisotropy_reaches_the_scene_readings():
    contacts = np.array([[100.0, 100.0, 8.0]])
    iso = scene({"contact_resistance": {}}).simulate(contacts).channels
    aniso = scene({"contact_resistance": {}, "fabric_anisotropy": {"ratio": 2.0}}).simulate(contacts).channels
    assert not np.allclose(iso, aniso)


def test_electrode_contact_impedance_drift_shows_only_on_current_carrying_readings():
    contacts = np.column_stack([np.full(30, 100.0), np.full(30, 100.0), np.full(30, 8.0)])
    plain = scene({"contact_resistance": {}}).simulate(contacts)
    steady = scene({"contact_resistance": {}, "electrode_contact_impedance": {"drift_fraction_per_50_presses": 0.0}}).simulate(contacts)
    assert np.allclose(steady.channels, plain.channels)                # a constant contact resistance cancels
    drifting = scene({"contact_resistance": {}, "electrode_contact_impedance": {}}).simulate(contacts)
    changed = np.abs(drifting.channels - plain.channels).max(axis=0) > 1e-12
    inj, meas = drifting.description["n_injections"], drifting.description["n_measurements"]
    s = scene({})
    injections, measurements = s.patterns()
    carries = np.array([[len({a, b} & {c, d}) > 0 for c, d in measurements] for a, b in injections]).ravel()
    assert changed.shape == (inj * meas,)
    assert changed[carries].all() and not changed[~carries].any()


def test_textile_contact_and_viscoelastic_hysteresis_in_the_scene():
    contacts = np.array([[100.0, 100.0, 2.0], [100.0, 100.0, 8.0], [100.0, 100.0, 14.0]])
    frame = scene({"textile_contact": {}}).simulate(contacts).channels
    size = np.abs(frame).max(axis=1)
    assert size[0] < size[1] < size[2]                                 # more force, more change
    plain = scene({"textile_contact": {}}).simulate(np.repeat(contacts, 20, axis=0)).channels
    lagged = scene({"textile_contact": {}, "viscoelastic_hysteresis": {}}).simulate(np.repeat(contacts, 20, axis=0)).channels
    spread = np.abs(lagged - plain).max(axis=1)
    assert spread.max() > 0 and not np.allclose(lagged, plain)
    again = scene({"textile_contact": {}, "viscoelastic_hysteresis": {}}).simulate(np.repeat(contacts, 20, axis=0)).channels
    assert np.array_equal(lagged, again)                               # same seed, same result


def test_restoring_baseline_drift_stays_bounded_where_the_random_walk_grows():
    from data.scenes.ert_effects import _walk
    walk = _walk(np.random.default_rng(0), 2000, 400, 0.0057, None)
    restoring = _walk(np.random.default_rng(0), 2000, 400, 0.0057, None, restoring_presses=10.0)
    # both change by the paper's 0.57 % over 50 presses; the walk keeps going, the fabric springs back
    assert (walk[149] - walk[99]).std() == pytest.approx(0.0057, rel=0.15)
    assert (restoring[149] - restoring[99]).std() == pytest.approx(0.0057, rel=0.15)
    assert walk[1999].std() > 5 * 0.0057
    assert restoring[1999].std() == pytest.approx(0.0057 / np.sqrt(1 - np.exp(-5.0)), rel=0.15)
    # a new recording's unloaded frame zeroes the drift there too
    split = _walk(np.random.default_rng(1), 20, 2000, 0.0057, np.repeat([0, 1], 10), restoring_presses=10.0)
    assert split[10].std() < 0.6 * split[9].std()            # one step from the new frame, against ten


def test_restoring_drift_in_the_scene_is_deterministic_and_differs_from_the_walk():
    contacts = np.tile([[100.0, 100.0, 8.0]], (40, 1))
    effects = {"contact_resistance": {}, "baseline_drift": {"fraction_per_50_presses": 0.05, "restoring_presses": 5.0}}
    a, b = scene(effects).simulate(contacts).channels, scene(effects).simulate(contacts).channels
    assert np.array_equal(a, b)
    walk = scene({"contact_resistance": {}, "baseline_drift": {"fraction_per_50_presses": 0.05}}).simulate(contacts).channels
    assert not np.allclose(a, walk)


def test_two_point_indenters_placed_by_hand_move_the_readings_not_the_marks():
    from runs.studies.ert_tests import placed_by_hand
    two = scene({"contact_resistance": {}, "foam_spread": {}}, protocol="two_point", n_repeats=2, distances_mm=(40,),
                two_point_locations_mm=((100.0, 100.0),))
    test = two.generate()
    moved = placed_by_hand(two, test, 2.0)
    assert moved.shape == test.channels.shape and not np.allclose(moved, test.channels)
    assert np.array_equal(moved, placed_by_hand(two, test, 2.0))
    assert np.allclose(placed_by_hand(two, test, 1e-12), test.channels, atol=1e-9 * np.abs(test.channels).max())
    from runs.studies.ert_tests import run_two_point
    with pytest.raises(InputError, match="placement_sd_mm must be >= 0"):
        run_two_point(None, "unused", None, placement_sd_mm=-1.0)


@pytest.mark.parametrize("effects", [
    {"textile_contact": {"saturated_fraction": 1.5}},
    {"textile_contact": {"initial_slope_per_n": 0.2}},
    {"contact_resistance": {}, "viscoelastic_hysteresis": {"relaxation_time_s": 0.0}},
    {"contact_resistance": {}, "electrode_contact_impedance": {"resistance_ohm": -1.0}},
    {"contact_resistance": {}, "fabric_anisotropy": {"ratio": -2.0}},
    {"contact_resistance": {}, "baseline_drift": {"restoring_presses": 0.0}},
])
def test_impossible_parameters_are_one_line_errors(effects):
    with pytest.raises(InputError, match="scene ert: effect"):
        scene(effects).simulate(np.array([[100.0, 100.0, 8.0]]))


# -- SVD-optimal injection: scores that do not depend on the SVD's basis -------------------------
def test_leading_subspace_scores_tie_whole_symmetry_orbits():
    from data.physics.optimal_injection import perturbation_operator, recruit_pairs
    from data.ert.jacobian import cell_jacobian
    ring = np.array([[20, 120], [60, 120], [100, 120], [120, 100], [120, 60], [120, 20], [100, 0], [60, 0], [20, 0],
                     [0, 20], [0, 60], [0, 100]], dtype=float)
    grid = SheetGrid(120.0, 25, ring, 0.0)
    op = perturbation_operator(cell_jacobian(SheetSolver(grid), 5e-5, 120.0, 20.0))
    index = {tuple(p): k for k, p in enumerate(ring)}
    symmetries = [lambda p: p, lambda p: [120 - p[0], p[1]], lambda p: [p[0], 120 - p[1]], lambda p: [p[1], p[0]]]

    def closed(group):
        pairs = {tuple(sorted(p)) for p in group.tolist()}
        return all(tuple(sorted((index[tuple(g(ring[a]))], index[tuple(g(ring[b]))]))) in pairs
                   for a, b in pairs for g in symmetries)
    subspace = recruit_pairs(op, 12, max_iterations=2, tie_tolerance=1e-6, score="leading_subspace")
    assert all(closed(group) for group in subspace.pairs_per_iteration)
    # the earlier score splits an orbit: its second group holds half of one
    basis = recruit_pairs(op, 12, max_iterations=2, tie_tolerance=1e-6, score="singular_vector")
    assert not closed(basis.pairs_per_iteration[1])
    with pytest.raises(ValueError):
        recruit_pairs(op, 12, max_iterations=1, score="best")
