"""The ERT skin scenes: silent without the transducer, local and reproducible with it, every
effect doing something, bad input one line, and finite readings at the extremes."""
import numpy as np
import pytest
from hydra.utils import instantiate
from hypothesis import given, settings
from hypothesis import strategies as st

from common.errors import InputError
from data.ert.protocol import injection_pairs
from data.scenes.ert import ERTScene
from data.scenes.ert_effects import EFFECTS
from models.ert.tikhonov import TikhonovReconstruction

BOUNDARY = [[20, 120], [60, 120], [100, 120], [120, 100], [120, 60], [120, 20], [100, 0], [60, 0], [20, 0],
            [0, 20], [0, 60], [0, 100]]
SMALL = dict(electrodes_mm=BOUNDARY, side_mm=120.0, grid_nodes=25, patch_mm=20.0)
ALL = {"specimen_variation": {}, "electrode_position_error": {}, "foam_spread": {}, "hysteresis": {},
       "contact_resistance": {}, "baseline_drift": {}, "adc_noise": {}}


def presses(contacts, effects=None, **kwargs):
    scene = ERTScene(effects={"contact_resistance": {}} if effects is None else effects, **{**SMALL, **kwargs})
    return scene.simulate(np.asarray(contacts, dtype=float))


def test_without_the_transducer_a_press_changes_nothing():
    table = presses([[60, 60, 10.0], [20, 30, 5.0]], effects={"foam_spread": {}})
    assert np.abs(table.channels).max() == 0.0


def test_a_press_changes_the_readings_more_near_it_and_more_with_force():
    table = presses([[30, 30, 5.0], [30, 30, 10.0], [90, 90, 10.0]])
    light, heavy, far = np.abs(table.channels)
    assert heavy.sum() > light.sum() > 0
    # electrodes 8-11 sit near (30, 30): injections between them respond more there than to (90, 90)
    near = [k for k, (a, b) in enumerate(injection_pairs("all", 12)) if a in (7, 8, 9, 10) and b in (7, 8, 9, 10)]
    per_injection = lambda row: row.reshape(66, 12)[near].sum()
    assert per_injection(heavy) > 3 * per_injection(far)


def test_mirror_symmetric_presses_give_permuted_readings_on_a_symmetric_layout():
    # Mirroring x -> 120 - x maps electrode k (0-based) onto (2 - k) mod 12 on this layout, the
    # measurement (c, c+1) onto -(c' - 1, c'), and the injection (a, b) onto (a', b').
    table = presses([[30, 70, 8.0], [90, 70, 8.0]], effects={"foam_spread": {}, "contact_resistance": {}})
    a, b = (row.reshape(66, 12) for row in table.channels)
    pairs = [tuple(p) for p in injection_pairs("all", 12)]
    mirror = lambda k: (2 - k) % 12
    expected = np.empty_like(a)
    for i, (p, q) in enumerate(pairs):
        pm, qm = mirror(p), mirror(q)
        sign = 1.0 if pm < qm else -1.0
        row = b[pairs.index((min(pm, qm), max(pm, qm)))]
        for c in range(12):
            expected[i, c] = -sign * row[(mirror(c) - 1) % 12]
    np.testing.assert_allclose(a, expected, rtol=1e-7, atol=1e-9 * np.abs(a).max())
    assert not np.allclose(a, b)


def test_same_seed_same_table_and_another_seed_differs():
    scene = lambda seed: ERTScene(protocol="random", n_samples=6, effects=ALL, seed=seed, **SMALL)
    a, b, c = scene(1).generate(), scene(1).generate(), scene(2).generate()
    np.testing.assert_array_equal(a.channels, b.channels)
    assert not np.allclose(a.channels, c.channels)


@pytest.mark.parametrize("effect", sorted(EFFECTS))
def test_every_effect_changes_the_readings(effect):
    base = {"contact_resistance": {}, "foam_spread": {}}
    if effect in base:   # compare with the effect off (the transducer: with another curve)
        other = {k: v for k, v in base.items() if k != effect}
        if effect == "contact_resistance":
            other["contact_resistance"] = {"initial_slope_per_n": 0.2}
    else:
        other = {**base, effect: {}}
    table = lambda effects: ERTScene(protocol="random", n_samples=12, effects=effects, seed=3, **SMALL).generate()
    assert not np.allclose(table(base).channels, table(other).channels)


def test_protocol_sizes_targets_and_groups():
    single = ERTScene(protocol="single_point", grid_points_per_side=4, n_force_levels=2, **SMALL).generate()
    assert len(single.frame) == 32 and single.target_columns == ["x_mm", "y_mm", "force_n"]
    assert len(np.unique(single.groups)) == 32
    two = ERTScene(protocol="two_point", two_point_locations_mm=[[60, 60]], distances_mm=[20, 40], n_repeats=2,
                   **SMALL).generate()
    assert len(two.frame) == 4
    np.testing.assert_allclose(two.frame["x2_mm"] - two.frame["x1_mm"], [20, 20, 40, 40])
    np.testing.assert_allclose(two.frame["force_n"], 16.0)


def test_the_paper_layouts_compose_with_276_injections_and_24_measurements(compose_config):
    for layout, n_internal in (("ert_boundary", 0), ("ert_internal", 4)):
        scene = instantiate(compose_config([f"scene={layout}"]).scene)
        xy = np.asarray(scene.electrodes_mm, dtype=float)
        assert len(xy) == 24 and len(scene.channel_names()) == 276 * 24
        inside = ((xy > 0) & (xy < 200)).all(axis=1)
        assert inside.sum() == n_internal


@pytest.mark.parametrize("kwargs, message", [
    ({"electrodes_mm": BOUNDARY[:-1] + [[130, 50]]}, "lies outside the 120 x 120 mm sheet"),
    ({"electrodes_mm": BOUNDARY[:-1] + [[1, 59]]}, "both cover the node"),
    ({"injection": [[1, 13]]}, r"injection pair \[1, 13\] names a missing electrode"),
    ({"injection": [[2, 2]]}, r"injection pair \[2, 2\]"),
    ({"measurement": "opposite"}, "unknown measurement pattern 'opposite'"),
    ({"protocol": "sweep"}, "scene.protocol must be one of"),
    ({"recording_presses": 0}, "recording_presses must be >= 1"),
    ({"effects": {"contact_resistance": {"saturated_fraction": 0.0}}}, "0 < saturated_fraction <= 1"),
    ({"effects": {"humidity": {}}}, "unknown effect 'humidity'"),
])
def test_bad_scene_input_is_one_line(kwargs, message):
    with pytest.raises(InputError, match=message):
        ERTScene(**{**SMALL, "grid_points_per_side": 2, "n_force_levels": 1, **kwargs}).generate()


def test_recordings_restart_the_baseline_drift_and_are_the_groups():
    contacts = np.tile([[60.0, 60.0, 8.0]], (12, 1))
    drift = {"contact_resistance": {}, "baseline_drift": {"fraction_per_50_presses": 0.5}}
    one = presses(contacts, effects=drift)
    split = presses(contacts, effects=drift, recording_presses=4)
    still = presses(contacts)                     # no drift: every frame the same
    assert np.array_equal(split.groups, np.repeat([0, 1, 2], 4))
    assert len(np.unique(one.groups)) == 12
    # the same draws, restarted: recording 3's first frame carries one step of the walk, not nine
    scale = np.abs(one.channels).max()
    assert np.allclose(split.channels[8] - still.channels[8], one.channels[8] - one.channels[7], atol=1e-9 * scale)
    drift_split = np.abs(split.channels - still.channels).sum(axis=1)
    drift_one = np.abs(one.channels - still.channels).sum(axis=1)
    assert drift_split[8] < drift_one[8]
    assert np.allclose(split.channels[:4], one.channels[:4])   # the first recording is unchanged


# -- property tests: finite readings and reconstructions at the extremes ---------------------------
@settings(max_examples=12)
@given(x=st.floats(0.0, 120.0), y=st.floats(0.0, 120.0), force=st.sampled_from([0.0, 1e-6, 5.0, 1e4]),
       slope=st.sampled_from([0.0, 0.0696, 50.0]), saturated=st.sampled_from([1e-6, 0.099, 1.0]))
def test_readings_are_finite_for_any_press_and_transducer(x, y, force, slope, saturated):
    effects = {"foam_spread": {}, "contact_resistance": {"initial_slope_per_n": slope, "saturated_fraction": saturated}}
    table = presses([[x, y, force]], effects=effects)
    assert np.isfinite(table.channels).all()
    if force == 0.0 or slope == 0.0 or saturated == 1.0:
        assert np.abs(table.channels).max() < 1e-9


@settings(max_examples=6)
@given(electrode=st.integers(0, 11), force=st.floats(0.0, 100.0))
def test_presses_on_an_electrode_and_coincident_indenters_stay_finite(electrode, force):
    x, y = BOUNDARY[electrode]
    contacts = np.array([[[x, y, force], [x, y, force]]])
    table = ERTScene(effects={"contact_resistance": {}}, **SMALL).simulate(contacts)
    assert np.isfinite(table.channels).all()
    single = presses([[x, y, 2 * force]])
    np.testing.assert_allclose(table.channels, single.channels, rtol=1e-9, atol=1e-12)


@pytest.fixture(scope="module")
def calibration():
    scene = ERTScene(protocol="calibration", grid_points_per_side=4, n_force_levels=2, force_range_n=(3.0, 12.0),
                     effects={"contact_resistance": {}}, **SMALL)
    return scene, scene.generate()


@settings(max_examples=4)
@given(alpha=st.sampled_from([1e-12, 1e-6, 1e3, 1e9]))
def test_extreme_alpha_gives_finite_predictions(calibration, alpha):
    scene, table = calibration
    model = TikhonovReconstruction(geometry=scene.geometry(), pixels_per_side=6, alpha_relative=(alpha,),
                                   deconvolution_sigma_mm=0.0).fit(table.channels, table.targets)
    prediction = model.predict(table.channels)
    assert np.isfinite(prediction).all()
    assert ((prediction[:, :2] >= 0) & (prediction[:, :2] <= 120)).all()
