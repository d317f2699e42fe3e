"""Scene `taxels` (seed 004): physics checks on the flat cover (eq. 3-4, each within 1 %), what
the finite layer and the surface structures do, the bridge read-out, the contract, bad input and
hard cases."""
import numpy as np
import pytest
from hydra.utils import instantiate
from hypothesis import given, settings
from hypothesis import strategies as st

from common.errors import InputError
from data.physics.bonded_layer import base_field, base_traction_pa, layer_kernels
from data.scenes.taxels import TaxelsScene
from runs.studies.taxel_receptive_field import fit_laws, profile_metrics

E_PA, FORCE_MN = 2.4e6, 10.0


def needle_profile(effects, thickness_um, n_points=3001, **kwargs):
    """eps_z of taxel 0 while a 10 mN load is scanned along its row, +/- 4 thicknesses around it."""
    scene = TaxelsScene(protocol="needle_scan", n_samples=n_points, effects=effects,
                        cover_thickness_um=thickness_um, needle_force_mn=FORCE_MN, **kwargs)
    centre = scene.taxel_xy_mm()[0, 0]
    reach = 4e-3 * thickness_um
    scene.scan_range_mm = (centre - reach, centre + reach)
    frame = scene.generate().frame
    return frame.x_mm.to_numpy(), frame.eps_z_t0.to_numpy(), centre


@pytest.mark.parametrize("thickness_um", [150.0, 580.0, 850.0])
def test_flat_cover_reproduces_eq3_and_eq4(thickness_um):
    """Seed 004 eq. (3)-(4) measured on the scene's profile, each within 1 %."""
    z_mm = thickness_um * 1e-3
    m = profile_metrics(*needle_profile({"flat": {}}, thickness_um))
    assert m["zero_crossing_mm"] == pytest.approx(np.sqrt(2) * z_mm, rel=0.01)
    assert m["width_mm"] == pytest.approx(2 * np.sqrt(2) * z_mm, rel=0.01)
    assert m["minimum_at_mm"] == pytest.approx(2 * z_mm, rel=0.01)
    assert m["ratio"] == pytest.approx(5**2.5, rel=0.01)
    assert m["amplitude"] == pytest.approx(3 * FORCE_MN * 1e-3 / (2 * np.pi * E_PA * (z_mm * 1e-3) ** 2), rel=0.01)


def test_flat_cover_laws_against_thickness():
    thickness = [150.0, 300.0, 580.0, 850.0]
    rows = [profile_metrics(*needle_profile({"flat": {}}, t, n_points=1501)) for t in thickness]
    laws = fit_laws(thickness, [r["width_mm"] for r in rows], [r["amplitude"] for r in rows])
    assert laws["w_slope"] == pytest.approx(2 * np.sqrt(2), rel=0.01)
    assert laws["a_exponent"] == pytest.approx(-2.0, rel=0.01)


def test_finite_layer_is_scale_free_and_concentrates_the_load():
    """A bonded layer under a point load has no length but h: A ~ h^-2 exactly, and the chip under
    the load carries ~1.57x the half-space value (the bonded base concentrates the stress). The
    paper's flatter law needs another length: the needle's and the plate's size flatten it."""
    thickness = [150.0, 300.0, 600.0]
    point = [profile_metrics(*needle_profile({"finite_layer": {}}, t, n_points=801)) for t in thickness]
    flat = profile_metrics(*needle_profile({"flat": {}}, 300.0, n_points=801))
    assert fit_laws(thickness, [np.nan] * 3, [r["amplitude"] for r in point])["a_exponent"] == pytest.approx(-2.0, rel=0.01)
    assert point[1]["amplitude"] / flat["amplitude"] == pytest.approx(1.571, rel=0.01)
    sized = {"needle": {"diameter_um": 100.0}, "plate_averaging": {"points_per_side": 3}, "finite_layer": {}}
    real = [profile_metrics(*needle_profile(sized, t, n_points=801))["amplitude"] for t in thickness]
    exponent = fit_laws(thickness, [np.nan] * 3, real)["a_exponent"]
    assert -2.0 < exponent < -1.45 - 0.05  # flatter than theory, not as flat as measured


def point_load_profile(interface, sensing, thickness_m=1.0, sensing_height_m=1e-6):
    """The eps_z(x) profile of a finite layer under a unit point load, as `finite_layer` senses it
    (x in units of h; scale-free but for the sensing height), and its eq. (3)-(4) metrics."""
    x = np.linspace(-5.0, 5.0, 4001)
    f = base_field(x * thickness_m, 0.0, thickness_m, 1.0, 0.0, 0.0, 0.5, interface)
    profile = f["sigma_zz"] if sensing == "traction" else f["eps_zz_2g"] - sensing_height_m * f["d_eps_zz_2g_dz"]
    return profile_metrics(x, profile, 0.0)


def test_finite_layer_models_against_the_papers_direction():
    """Seed 004 measured W = 1.14 h (half-space 2.83 h) and |eps_max/eps_min| ~ 19 (56). Point
    loads, so W/h is the slope of W against thickness. What each physically grounded finite layer
    gives (docs/taxels.md): none reproduces the narrower AND more inhibited profile together with
    the flatter amplitude law."""
    half_space_w, half_space_ratio = 2 * np.sqrt(2), 5**2.5
    bonded = point_load_profile("bonded", "traction")
    assert bonded["width_mm"] > 1.15 * half_space_w and bonded["ratio"] > 1000   # wider, no lobe
    slipping = point_load_profile("frictionless", "traction")
    assert slipping["width_mm"] > 1.05 * half_space_w and slipping["ratio"] > 2 * half_space_ratio
    # The rubber's strain on a frictionless chip: narrower (2.51 h), but no stronger inhibition.
    slipping_strain = point_load_profile("frictionless", "cover_strain")
    assert 0.8 * half_space_w < slipping_strain["width_mm"] < 0.95 * half_space_w
    assert slipping_strain["ratio"] == pytest.approx(half_space_ratio, rel=0.02)
    # The rubber's strain just above a bonded chip: narrower (1.47 h) and more inhibited (14),
    # near the paper's 1.14 h and 19 ...
    bonded_strain = point_load_profile("bonded", "cover_strain")
    assert 1.14 < bonded_strain["width_mm"] < 1.4 * 1.14
    assert 19.0 / 1.5 < bonded_strain["ratio"] < 19.0
    # ... but its amplitude falls as h^-3 (first order in the sensing height), away from the
    # paper's -1.45: the direction of A is not reproduced.
    thickness = np.array([150.0, 300.0, 600.0, 1000.0])
    amplitude = [point_load_profile("bonded", "cover_strain", t * 1e-6, 1e-7)["amplitude"] for t in thickness]
    assert fit_laws(thickness, [np.nan] * 4, amplitude)["a_exponent"] == pytest.approx(-3.0, rel=0.01)


def test_finite_layer_scene_slopes_against_thickness():
    """The scene's own needle-scan profiles (point loads): the W slope and A exponent above."""
    thickness = [150.0, 400.0, 850.0]
    for effect, slope, exponent in (({"interface": "frictionless", "sensing": "cover_strain"}, 2.509, -2.0),
                                    ({"sensing": "cover_strain", "sensing_height_um": 10.0}, 1.466, -3.0)):
        rows = [profile_metrics(*needle_profile({"finite_layer": effect}, t, n_points=801)) for t in thickness]
        laws = fit_laws(thickness, [r["width_mm"] for r in rows], [r["amplitude"] for r in rows])
        assert laws["w_slope"] == pytest.approx(slope, rel=0.02)
        assert laws["a_exponent"] == pytest.approx(exponent, rel=0.01)


def membrane(side_um, points_per_side=4):
    return {"needle": {"diameter_um": 100.0}, "plate_averaging": {"points_per_side": points_per_side,
                                                                  "side_um": side_um}, "flat": {}}


def membrane_features(side_um, thickness=(150.0, 400.0, 1000.0), points_per_side=4):
    """The ratio and shear sensitivity at 180 um, and the W slope and A exponent over `thickness`."""
    x, eps, centre = needle_profile(membrane(side_um, points_per_side), 180.0, n_points=801)
    fig2 = profile_metrics(x, eps, centre)
    rows = [profile_metrics(*needle_profile(membrane(side_um, points_per_side), t, n_points=801)) for t in thickness]
    laws = fit_laws(thickness, [r["width_mm"] for r in rows], [r["amplitude"] for r in rows])
    scene = TaxelsScene(protocol="needle_scan", n_samples=801, effects=membrane(side_um, points_per_side),
                        cover_thickness_um=180.0, scan_range_mm=(-0.75 - 0.72, -0.75 + 0.72))
    frame = scene.generate().frame
    shear = np.abs(frame.gamma_x_t0).max() / np.abs(frame.eps_z_t0).max()
    return {"ratio": fig2["ratio"], "shear": shear, **laws}


def test_membrane_averaging_moves_toward_the_measurement():
    """Eq. (1)'s strain averaged over the taxel's membrane (the default's mechanics): the larger the
    membrane, the stronger the lateral inhibition, the flatter the amplitude law and the narrower
    the field (the paper's direction for all three), while the shear sensitivity rises (away from
    it). At the default 350 um the ratio and exponent fall within the paper's tolerances."""
    point = {"ratio": 5**2.5, "shear": 0.75 * 0.8**2.5, "w_slope": 2 * np.sqrt(2), "a_exponent": -2.0}
    small, default, large = (membrane_features(side) for side in (100.0, 350.0, 500.0))
    for key in ("ratio", "w_slope"):
        assert point[key] > small[key] > default[key] > large[key]
    assert point["a_exponent"] < small["a_exponent"] < default["a_exponent"] < large["a_exponent"]
    assert point["shear"] < small["shear"] < default["shear"] < large["shear"]
    assert 19.0 * 0.7 < default["ratio"] < 19.0 * 1.3
    assert abs(default["a_exponent"] + 1.45) < 0.25
    assert 1.14 < default["w_slope"] < 0.97 * 2 * np.sqrt(2)


def test_membrane_quadrature_has_converged():
    """4 x 4 Gauss points (the default) against 12 x 12 on the 350 um membrane."""
    coarse, fine = membrane_features(350.0, (150.0, 1000.0)), membrane_features(350.0, (150.0, 1000.0), 12)
    for key in ("ratio", "w_slope", "a_exponent"):
        assert coarse[key] == pytest.approx(fine[key], rel=0.02)


def test_membrane_average_is_the_area_mean_of_eq1():
    """The default's sensing: eq. (1)'s eps_z written out here, averaged over the 350 um square by a
    dense midpoint rule, against the scene's Gauss points (8 x 8 here; the default's 4 x 4 is
    within 2 % of this under the load at 180 um), for point loads on and off the taxel."""
    side, z, force = 350e-6, 180e-6, 10e-3
    scene = TaxelsScene(n_taxels_side=1, effects={"plate_averaging": {"points_per_side": 8, "side_um": 350.0},
                                                  "flat": {}}, cover_thickness_um=180.0)
    grid = (np.arange(400) + 0.5) / 400 * side - side / 2
    gx, gy = np.meshgrid(grid, grid)
    for load_mm in (0.0, 0.2, 0.45):
        x = gx - load_mm * 1e-3
        eq1 = 3 * force * z * (x**2 + gy**2 - 2 * z**2) / (4 * np.pi * E_PA * (x**2 + gy**2 + z**2) ** 2.5)
        scene_value = scene.simulate([load_mm], [0.0], force * 1e3).frame.eps_z_t0[0]
        assert scene_value == pytest.approx(eq1.mean(), rel=0.005)


def test_plate_averaging_defaults_to_the_plate():
    scene = TaxelsScene(effects={"plate_averaging": {"points_per_side": 3}, "flat": {}})
    same = TaxelsScene(effects={"plate_averaging": {"points_per_side": 3, "side_um": 100.0}, "flat": {}})
    other = TaxelsScene(effects={"plate_averaging": {"points_per_side": 3, "side_um": 350.0}, "flat": {}})
    args = ([-0.5, 0.1], [-0.7, 0.3], 5.0, 0.5, -0.2)
    np.testing.assert_array_equal(scene.simulate(*args).channels, same.simulate(*args).channels)
    assert not np.allclose(scene.simulate(*args).channels, other.simulate(*args).channels)


def test_base_strain_kernels_obey_incompressibility():
    """At nu = 0.5 a bonded face cannot strain (eps_zz = 0), and just above it d eps_zz/dz =
    -div(tau) / G, tau the base shear traction (checked by finite differences of tau); on a
    frictionless base the shear traction vanishes and the whole load still reaches the chip."""
    x = np.linspace(-3.0, 3.0, 1201)
    for load in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)):
        f = base_field(x, 0.3, 1.0, *load, 0.5, "bonded")
        up, down = (base_field(x, 0.3 + step, 1.0, *load, 0.5, "bonded") for step in (0.02, -0.02))
        divergence = np.gradient(f["sigma_xz"], x) + (up["sigma_yz"] - down["sigma_yz"]) / 0.04
        np.testing.assert_allclose(f["d_eps_zz_2g_dz"], -2 * divergence, atol=0.01 * np.abs(divergence).max())
        assert np.abs(f["eps_zz_2g"]).max() < 1e-9
    r, k = layer_kernels(0.5, "frictionless")
    assert np.trapezoid(k["zz"] * 2 * np.pi * r, r) == pytest.approx(-1.0, abs=0.005)
    f = base_field(x, 0.2, 1.0, 1.0, 0.0, 0.0, 0.5, "frictionless")
    assert np.abs(np.r_[f["sigma_xz"], f["sigma_yz"]]).max() < 1e-12
    assert np.abs(f["eps_zz_2g"]).max() > 0.1


def test_base_strain_reproduces_the_half_space():
    """The new strain rows against Boussinesq + Cerruti with the base removed (nu = 0.3)."""
    from data.physics.elastic_half_space import displacement_gradient
    nu, dz = 0.3, 1e-4
    shear_modulus = 1 / (2 * (1 + nu))
    for x, y in [(0.3, 0.2), (1.0, -0.5)]:
        f = base_field(x, y, 1.0, 0.8, 0.5, -0.3, nu, "half_space")
        g = displacement_gradient(x, y, 1.0, 0.8, 0.5, -0.3, 1.0, nu)[2, 2]
        g_below = displacement_gradient(x, y, 1.0 + dz, 0.8, 0.5, -0.3, 1.0, nu)[2, 2]
        assert f["eps_zz_2g"] / (2 * shear_modulus) == pytest.approx(g, rel=1e-3)
        assert f["d_eps_zz_2g_dz"] / (2 * shear_modulus) == pytest.approx((g_below - g) / dz, rel=2e-3)


def test_bonded_layer_carries_the_whole_load():
    r, k = layer_kernels(0.5)
    assert np.trapezoid(k["zz"] * 2 * np.pi * r, r) == pytest.approx(-1.0, abs=0.005)
    assert np.trapezoid(k["q0"] * 2 * np.pi * r, r) == pytest.approx(-1.0, abs=0.005)


def test_bonded_layer_machinery_reproduces_the_half_space():
    """The same transform with the base removed gives Boussinesq + Cerruti at depth h."""
    from data.physics.elastic_half_space import displacement_gradient
    nu = 0.3
    for x, y in [(0.3, 0.2), (1.0, -0.5), (-0.7, 1.3), (0.0, 0.0)]:
        g = displacement_gradient(x, y, 1.0, 0.8, 0.5, -0.3, 1.0, nu)
        eps = 0.5 * (g + g.T)
        shear_modulus = 1 / (2 * (1 + nu))
        lam = 2 * shear_modulus * nu / (1 - 2 * nu)
        sigma = 2 * shear_modulus * eps + lam * np.trace(eps) * np.eye(3)
        got = base_traction_pa(x, y, 1.0, 0.8, 0.5, -0.3, nu, base="half_space")
        np.testing.assert_allclose(got, sigma[:, 2], atol=1e-3 * np.abs(sigma).max())


def test_bridges_invert_eq2_exactly():
    scene = TaxelsScene(effects={"flat": {}})
    rng = np.random.default_rng(0)
    strain = rng.normal(0, 1e-3, (5, 4, 3))
    bridges = scene.bridges_mv(strain)
    np.testing.assert_allclose(scene.strain_from_bridges(bridges), strain, rtol=1e-12)
    alpha_n, alpha_s = scene.bridge_constants()
    v = bridges.reshape(5, 4, 4)
    np.testing.assert_allclose(alpha_s * (v[..., 0] - v[..., 1]), strain[..., 0], rtol=1e-12)
    np.testing.assert_allclose(alpha_n / 2 * v.sum(-1), strain[..., 2], rtol=1e-12)


def test_bumps_raise_the_response_to_a_broad_load():
    """Seed 004 Fig. 9: a fingertip-sized probe rests on the bumps, which concentrate its load."""
    rng = np.random.default_rng(0)
    x, y = rng.uniform(-0.3, 0.3, (2, 50))
    flat = TaxelsScene(effects={"needle": {"diameter_um": 3000.0, "rings": 6, "points_per_ring": 16},
                                "finite_layer": {}}, cover_thickness_um=200.0)
    bumps = TaxelsScene(effects={"bump": {"probe_diameter_um": 3000.0}, "finite_layer": {}}, cover_thickness_um=200.0)
    shear_flat = np.abs(flat.simulate(x, y, 0.0, 1.0, 0.0).frame.gamma_x_t0).mean()
    shear_bump = np.abs(bumps.simulate(x, y, 0.0, 1.0, 0.0).frame.gamma_x_t0).mean()
    assert shear_bump > 3 * shear_flat


def test_bump_collects_loads_over_its_footprint():
    """A load anywhere on the bump reaches the layer as the same resultant above the taxel."""
    scene = TaxelsScene(effects={"bump": {"height_um": 0.0}, "flat": {}}, cover_thickness_um=200.0)
    centre = scene.taxel_xy_mm()[0]
    frame = scene.simulate([centre[0], centre[0] + 0.05], [centre[1], centre[1]], 10.0).frame
    plain = TaxelsScene(effects={"flat": {}}, cover_thickness_um=200.0).simulate(
        [centre[0], centre[0] + 0.05], [centre[1], centre[1]], 10.0).frame
    spread_on_bump = abs(frame.eps_z_t0[1] / frame.eps_z_t0[0] - 1)
    spread_flat = abs(plain.eps_z_t0[1] / plain.eps_z_t0[0] - 1)
    assert spread_on_bump < 0.2 * spread_flat


def moving_shear_peak(effects, direction_deg):
    scene = TaxelsScene(protocol="moving_loads", n_samples=601, effects=effects,
                        directions_deg=[direction_deg], cover_thickness_um=200.0)
    frame = scene.generate().frame
    component = "gamma_x_t0" if direction_deg == 0.0 else "gamma_y_t0"
    return np.abs(frame[component]).max()


def test_ridge_is_direction_selective():
    """Seed 004 Fig. 10c-d: a ridge along x answers a load moved across it (along y) with its
    shear, and one moved along it much less; the flat cover is isotropic."""
    ridge = {"ridge": {"orientation_deg": 0.0}, "finite_layer": {}}
    flat = {"finite_layer": {}}
    selectivity = moving_shear_peak(ridge, 90.0) / moving_shear_peak(ridge, 0.0)
    isotropy = moving_shear_peak(flat, 90.0) / moving_shear_peak(flat, 0.0)
    assert isotropy == pytest.approx(1.0, rel=1e-6)
    assert selectivity > 1.5


def test_hair_makes_shear_dominate():
    """Seed 004 Fig. 6: with a rod on the plate, shear dominates the reading."""
    hair = moving_shear_peak({"hair": {}, "finite_layer": {}}, 0.0)
    frame = TaxelsScene(protocol="moving_loads", n_samples=601, effects={"hair": {}, "finite_layer": {}},
                        directions_deg=[0.0]).generate().frame
    assert hair > 2 * np.abs(frame.eps_z_t0).max()
    flat = TaxelsScene(protocol="moving_loads", n_samples=601, effects={"finite_layer": {}},
                       directions_deg=[0.0]).generate().frame
    assert np.abs(flat.gamma_x_t0).max() < np.abs(flat.eps_z_t0).max()


def test_same_seed_same_table_and_effects_keep_their_own_random_numbers(compose_config):
    cfg = compose_config(["scene=taxels", "scene.n_samples=64"])
    first, second = instantiate(cfg.scene).generate(), instantiate(cfg.scene).generate()
    np.testing.assert_array_equal(first.channels, second.channels)
    other = instantiate(compose_config(["scene=taxels", "scene.n_samples=64", "seed=1"]).scene).generate()
    assert not np.array_equal(first.channels, other.channels)
    no_adc = instantiate(compose_config(["scene=taxels", "scene.n_samples=64", "~scene.effects.adc"]).scene).generate()
    lsb = 2 * 5000.0 / 2**12
    assert np.abs(first.channels - no_adc.channels).max() <= lsb / 2 + 1e-9


@pytest.mark.parametrize("variant", ["taxels", "taxels_flat", "taxels_minimal", "taxels_bump", "taxels_ridge", "taxels_hair"])
@pytest.mark.parametrize("protocol", ["random_loads", "needle_scan", "thickness_series", "moving_loads"])
def test_every_variant_and_protocol_gives_a_finite_table(compose_config, variant, protocol):
    cfg = compose_config([f"scene={variant}", f"scene.protocol={protocol}", "scene.n_samples=16"])
    table = instantiate(cfg.scene).generate()
    assert table.channels.shape == (16, 16)
    assert np.isfinite(table.channels).all() and np.isfinite(table.targets).all()
    assert table.target_columns == ["x_mm", "y_mm", "normal_n", "shear_x_n", "shear_y_n"]
    assert np.abs(table.channels).max() > 0  # every variant responds


def test_base_scene_reads_nothing(compose_config):
    table = instantiate(compose_config(["scene=base/taxels", "scene.n_samples=10"]).scene).generate()
    assert np.all(table.channels == 0)


LAYER = ["~scene.effects.flat", "+scene.effects.finite_layer={}"]   # the default chain on the finite layer


@pytest.mark.parametrize("overrides, message", [
    (["+scene.effects.velvet={}"], "unknown effect 'velvet'"),
    (["scene.cover_thickness_um=0"], "thickness"),
    (["scene.cover_thickness_um=-100"], "thickness"),
    (["scene.poisson_ratio=0.6"], "poisson_ratio"),
    (["scene.poisson_ratio=0"], "poisson_ratio"),
    (["scene.protocol=tapping"], "protocol"),
    (["scene.thickness_series_um=[100,0]"], "thickness"),
    (["+scene.effects.finite_layer={}"], "list only one"),
    (["+scene.effects.bump={}", "+scene.effects.ridge={}"], "list only one"),
    (["+scene.effects.bump={diameter_um: 2000}"], "pitch"),
    (["scene.pitch_mm=-1"], "pitch_mm"),
    (["scene.effects.plate_averaging.side_um=0"], "side_um"),
    (["scene.effects.plate_averaging.side_um=-350"], "side_um"),
    (["scene.effects.plate_averaging.pressure_moment=sometimes"], "pressure_moment"),
    (LAYER + ["+scene.effects.finite_layer.interface=glued"], "interface"),
    (LAYER + ["+scene.effects.finite_layer.interface=frictionless"], "cannot carry a shear load"),
    (LAYER + ["+scene.effects.finite_layer.sensing=cover_strain"], "does not strain"),
    (LAYER + ["+scene.effects.finite_layer.sensing_height_um=10"], "sensing_height_um"),
    (LAYER + ["+scene.effects.finite_layer.sensing=cover_strain", "+scene.effects.finite_layer.sensing_height_um=600"],
     "below the cover thickness"),
])
def test_bad_input_is_one_line(compose_config, overrides, message):
    cfg = compose_config(["scene=taxels", "scene.n_samples=8"] + overrides)
    with pytest.raises(InputError, match=message) as error:
        instantiate(cfg.scene).generate()
    assert "\n" not in str(error.value)


position = st.one_of(st.sampled_from([-0.75, 0.75, 0.0, -0.75 + 1e-12]), st.floats(-3.0, 3.0))


@settings(max_examples=40)
@given(x=position, y=position, thickness=st.one_of(st.sampled_from([1e-3, 100.0, 1000.0]), st.floats(1e-3, 2000.0)),
       normal=st.floats(0.0, 20.0), shear=st.tuples(st.floats(-5, 5), st.floats(-5, 5)),
       cover=st.sampled_from(["flat", "finite_layer", "cover_strain"]), surface=st.sampled_from([None, "bump", "ridge", "hair"]))
def test_any_load_gives_finite_readings(x, y, thickness, normal, shear, cover, surface):
    """Loads exactly over a taxel, covers down to 1 nm (the half-space's singular point: its
    documented core rule keeps it finite), any shear: every reading is finite."""
    effects = {cover: {}} if cover != "cover_strain" else {
        "finite_layer": {"sensing": "cover_strain", "sensing_height_um": min(10.0, 0.1 * thickness)}}
    if surface:
        effects[surface] = {}
    scene = TaxelsScene(effects=effects, cover_thickness_um=thickness)
    table = scene.simulate([x], [y], normal, *shear)
    assert np.isfinite(table.channels).all()
    assert np.isfinite(table.frame.filter(regex="^(gamma|eps)").to_numpy()).all()


def test_zero_force_reads_zero_and_readings_are_linear_in_force():
    scene = TaxelsScene(effects={"needle": {}, "finite_layer": {}, "bump": {}})
    one = scene.simulate([-0.7], [-0.6], 1.0, 0.2, -0.1).channels
    three = scene.simulate([-0.7], [-0.6], 3.0, 0.6, -0.3).channels
    np.testing.assert_allclose(three, 3 * one, rtol=1e-10)
    assert np.all(scene.simulate([-0.7], [-0.6], 0.0).channels == 0)


def test_receptive_field_study_writes_its_figures(compose_config, tmp_path):
    from runs.run import run
    cfg = compose_config(["experiment=taxel_receptive_field", "study.thickness_um=[150,300,600]",
                          "study.n_points=201", "~study.models.scene", "~study.models.half_space_real",
                          "~study.models.bonded_layer_real", "~study.models.bonded_layer",
                          "~study.models.frictionless_strain", "~study.models.bonded_cover_strain",
                          "~study.models.membrane",
                          "~study.models.frictionless_strain_real", "~study.models.bonded_cover_strain_real"])
    metrics = run(cfg, tmp_path)
    for name in ("receptive_field.png", "thickness.png", "thickness.csv", "profiles.csv", "metrics.json"):
        assert (tmp_path / name).stat().st_size > 0
    assert any((tmp_path / "tensorboard").iterdir())
    assert metrics["half_space"]["a_exponent"] == pytest.approx(-2.0, rel=0.01)
    assert metrics["half_space"]["w_slope"] == pytest.approx(2 * np.sqrt(2), rel=0.02)
    assert metrics["paper"] == {"w_slope": 1.14, "a_exponent": -1.45, "ratio": 19.0}


@pytest.mark.slow  # ~12 s: a whole regression run (fit, report, figures)
def test_inverse_runs_through_the_shared_regression_pipeline(compose_config, tmp_path):
    """experiment=taxel_inverse's single job (one cover, one thickness, one seed), tiny."""
    from runs.run import run
    cfg = compose_config(["experiment=taxel_inverse", "scene=taxels_ridge", "scene.cover_thickness_um=580",
                          "scene.n_samples=300", "model.n_estimators=10"])
    metrics = run(cfg, tmp_path)
    assert set(metrics["test"]) >= {"x_mm", "y_mm", "normal_n", "shear_x_n", "shear_y_n"}
    assert metrics["val"]["x_mm"]["r2"] > 0.3  # position is learnable from the bridges
