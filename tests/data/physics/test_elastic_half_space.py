"""The elastic half-space (data/physics/elastic_half_space.py) against its own equations.

Independent checks: elasticity's field equations (equilibrium, traction-free surface) evaluated
by finite differences, the resultant force carried across a plane, seed 004's eq. (1) at
nu = 0.5, its consequences eq. (3)-(4), and the singular point's documented rule.
"""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from common.errors import InputError
from data.physics.elastic_half_space import (
    DEFAULT_CORE_RADIUS_M,
    disc_quadrature,
    displacement_gradient,
    distributed_load_strain,
    point_load_strain,
    vertical_stress_pa,
)

E_PA = 2.4e6  # Elastosil, seed 004


def stress_pa(point, loads, nu, e_pa=E_PA):
    """Cauchy stress from Hooke's law (nu < 0.5 only: the pressure is indeterminate at 0.5)."""
    f = point_load_strain(*point, *loads, e_pa, nu)
    eps = np.stack([np.stack([f.eps_xx, f.eps_xy, f.eps_xz], -1), np.stack([f.eps_xy, f.eps_yy, f.eps_yz], -1),
                    np.stack([f.eps_xz, f.eps_yz, f.eps_zz], -1)], -2)
    shear_modulus = e_pa / (2 * (1 + nu))
    lam = 2 * shear_modulus * nu / (1 - 2 * nu)
    return 2 * shear_modulus * eps + lam * np.trace(eps, axis1=-2, axis2=-1)[..., None, None] * np.eye(3)


@pytest.mark.parametrize("nu", [0.1, 0.3, 0.45])
def test_equilibrium_by_finite_differences(nu):
    point = np.array([0.3e-3, -0.2e-3, 0.4e-3])
    loads = (0.01, 0.004, -0.007)
    h = 1e-8
    divergence = np.zeros(3)
    for j in range(3):
        step = np.zeros(3)
        step[j] = h
        divergence += (stress_pa(point + step, loads, nu)[:, j] - stress_pa(point - step, loads, nu)[:, j]) / (2 * h)
    scale = np.abs(stress_pa(point, loads, nu)).max() / np.linalg.norm(point)
    assert np.abs(divergence).max() < 1e-5 * scale


@pytest.mark.parametrize("nu", [0.2, 0.5])
def test_surface_is_traction_free_away_from_the_load(nu):
    if nu == 0.5:  # sigma_zj at the surface needs no pressure term: the shears and sigma_zz from strain
        g = displacement_gradient(0.2e-3, 0.1e-3, 0.0, 0.01, 0.003, 0.002, E_PA, nu)
        assert abs(g[0, 2] + g[2, 0]) < 1e-12 and abs(g[1, 2] + g[2, 1]) < 1e-12
        return
    s = stress_pa((0.2e-3, 0.1e-3, 0.0), (0.01, 0.003, 0.002), nu)
    assert np.abs(s[2]).max() < 1e-9 * np.abs(s).max()


def test_vertical_stress_carries_the_load_across_a_plane():
    depth = 0.5e-3
    r = np.linspace(0, 200 * depth, 400001)
    sigma = vertical_stress_pa(r, 0.0, depth, 0.01)
    carried = np.trapezoid(sigma * 2 * np.pi * r, r)
    assert carried == pytest.approx(0.01, rel=1e-3)


def test_shear_resultant_has_the_applied_sign_and_size():
    """sigma_xz integrated over a plane equals -Q (the upper slab's share of the load, nu = 0.3)."""
    depth = 1e-3
    g = np.linspace(-60e-3, 60e-3, 1201)
    xs, ys = np.meshgrid(g, g)
    s = stress_pa((xs, ys, np.full_like(xs, depth)), (0.0, 0.01, 0.0), 0.3)
    carried = s[..., 2, 0].sum() * (g[1] - g[0]) ** 2
    assert carried == pytest.approx(-0.01, rel=0.03)  # the far-field tail beyond 60 mm is ~2 %


def test_seed_eq1_at_nu_half():
    rng = np.random.default_rng(1)
    x, y = rng.uniform(-1e-3, 1e-3, (2, 50))
    z = rng.uniform(0.1e-3, 1e-3, 50)
    F, Q = 0.01, 0.004
    field = point_load_strain(x, y, z, F, Q, 0.0, E_PA, 0.5)
    R5 = (x * x + y * y + z * z) ** 2.5
    common = 3 * (Q * x + F * z) / (4 * np.pi * E_PA * R5)
    np.testing.assert_allclose(field.eps_zz, common * (x * x + y * y - 2 * z * z), rtol=1e-10)
    # The paper's gamma_x, gamma_y are the tensor shears with the opposite sign.
    np.testing.assert_allclose(-field.eps_xz, common * 3 * x * z, rtol=1e-10)
    np.testing.assert_allclose(-field.eps_yz, common * 3 * y * z, rtol=1e-10)


def test_incompressible_at_nu_half():
    f = point_load_strain(0.3e-3, 0.1e-3, 0.2e-3, 0.01, 0.002, -0.003, E_PA, 0.5)
    assert abs(f.eps_xx + f.eps_yy + f.eps_zz) < 1e-12 * abs(f.eps_zz)


def test_eq3_eq4_consequences_of_the_half_space():
    """Zero crossing at sqrt(2) z, minimum at 2 z, ratio 5^(5/2), width 2 sqrt(2) z, peak 3F/(2 pi E z^2)."""
    z, F = 0.58e-3, 0.01
    x = np.linspace(0, 4 * z, 400001)
    eps = point_load_strain(x, 0.0, z, F, 0.0, 0.0, E_PA, 0.5).eps_zz
    crossing = x[np.argmax(eps > 0)]
    minimum_at = x[np.argmax(eps)]  # the compressive peak's opposite: the tensile lobe's extreme
    assert crossing == pytest.approx(np.sqrt(2) * z, rel=1e-3)
    assert 2 * crossing == pytest.approx(2 * np.sqrt(2) * z, rel=1e-3)
    assert minimum_at == pytest.approx(2 * z, rel=1e-3)
    assert abs(eps[0] / eps.max()) == pytest.approx(5 ** 2.5, rel=1e-3)
    assert abs(eps[0]) == pytest.approx(3 * F / (2 * np.pi * E_PA * z**2), rel=1e-9)


def test_singular_point_follows_the_documented_rule():
    a = DEFAULT_CORE_RADIUS_M
    assert vertical_stress_pa(0.0, 0.0, 0.0, 1.0) == pytest.approx(3 / (2 * np.pi * a * a))
    for nu in (0.3, 0.5):
        at_point = point_load_strain(0.0, 0.0, 0.0, 1.0, 0.0, 0.0, E_PA, nu).eps_zz
        below = point_load_strain(0.0, 0.0, a, 1.0, 0.0, 0.0, E_PA, nu).eps_zz
        assert at_point == below
        assert below == pytest.approx(-(3 - 2 * nu) * (1 + nu) / (2 * np.pi * E_PA * a * a))
    # Outside the core the rule changes nothing.
    assert vertical_stress_pa(0.0, 0.0, 2 * a, 1.0) == pytest.approx(3 / (2 * np.pi * 4 * a * a))


def test_broadcasting_loads_against_taxels():
    loads_x = np.linspace(-1e-3, 1e-3, 7)[:, None]
    taxels_x = np.array([-0.75e-3, 0.75e-3])[None, :]
    f = point_load_strain(taxels_x - loads_x, 0.0, 0.3e-3, np.full((7, 1), 0.01), 0.0, 0.0, E_PA, 0.5)
    assert f.eps_zz.shape == (7, 2)
    single = point_load_strain(taxels_x[0, 1] - loads_x[3, 0], 0.0, 0.3e-3, 0.01, 0.0, 0.0, E_PA, 0.5)
    assert f.eps_zz[3, 1] == single.eps_zz


def test_distributed_load_tends_to_the_point_load_far_away():
    far = distributed_load_strain(0.0, 0.0, 2e-3, 0.01, 0.0, 0.0, E_PA, 0.5, contact_radius_m=50e-6)
    point = point_load_strain(0.0, 0.0, 2e-3, 0.01, 0.0, 0.0, E_PA, 0.5)
    assert far.eps_zz == pytest.approx(point.eps_zz, rel=1e-3)
    x, y, w = disc_quadrature(1e-3)
    assert w.sum() == pytest.approx(1.0) and np.all(np.hypot(x, y) < 1e-3)


def test_uniform_disc_on_axis_matches_johnson():
    """sigma_zz below a uniform circular pressure (Johnson eq. 3.?): p (1 - z^3/(a^2+z^2)^1.5)."""
    a, z, P = 0.3e-3, 0.4e-3, 0.01
    x, y, w = disc_quadrature(a, rings=60, points_per_ring=24)
    sigma = np.sum(vertical_stress_pa(-x, -y, z, P * w))
    p = P / (np.pi * a * a)
    assert sigma == pytest.approx(p * (1 - z**3 / (a * a + z * z) ** 1.5), rel=1e-3)


@pytest.mark.parametrize("nu", [0.0, -0.1, 0.5000001, 0.7, float("nan")])
def test_poisson_ratio_outside_range_is_input_error(nu):
    with pytest.raises(InputError, match="Poisson"):
        point_load_strain(0.0, 0.0, 1e-3, 1.0, 0.0, 0.0, E_PA, nu)


def test_other_bad_inputs_are_one_line_errors():
    with pytest.raises(InputError, match="Young"):
        point_load_strain(0.0, 0.0, 1e-3, 1.0, 0.0, 0.0, -1.0, 0.5)
    with pytest.raises(InputError, match="depth"):
        vertical_stress_pa(0.0, 0.0, -1e-3, 1.0)
    with pytest.raises(InputError, match="pressure_profile"):
        distributed_load_strain(0.0, 0.0, 1e-3, 1.0, 0.0, 0.0, E_PA, 0.5, 1e-4, pressure_profile="cone")


coordinate = st.one_of(st.sampled_from([0.0, 1e-12, -1e-12, 5e-324]), st.floats(-5e-3, 5e-3))
depth = st.one_of(st.sampled_from([0.0, 1e-12, 5e-324, DEFAULT_CORE_RADIUS_M]), st.floats(0.0, 5e-3))
poisson = st.one_of(st.sampled_from([0.5, 0.4999999, 1e-6]), st.floats(1e-6, 0.5))


@settings(max_examples=300)
@given(x=coordinate, y=coordinate, z=depth, nu=poisson,
       loads=st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)))
def test_fields_are_finite_everywhere(x, y, z, nu, loads):
    field = point_load_strain(x, y, z, *loads, E_PA, nu)
    assert all(np.isfinite(c) for c in field)
    assert np.isfinite(vertical_stress_pa(x, y, z, loads[0]))
    assert vertical_stress_pa(x, y, z, 1.0) >= 0.0


@settings(max_examples=100)
@given(x=st.floats(-2e-3, 2e-3), y=st.floats(-2e-3, 2e-3), z=st.floats(1e-5, 2e-3))
def test_nu_half_is_the_limit_of_nu_below_half(x, y, z):
    at = np.array(point_load_strain(x, y, z, 0.01, 0.003, -0.002, E_PA, 0.5))
    near = np.array(point_load_strain(x, y, z, 0.01, 0.003, -0.002, E_PA, 0.5 - 1e-9))
    assert np.allclose(at, near, rtol=1e-6, atol=1e-6 * np.abs(at).max())


@pytest.mark.parametrize("nu", [0.5, 0.3, 0.05])
def test_closed_form_strain_matches_the_displacement_gradient(nu):
    rng = np.random.default_rng(3)
    x, y = rng.uniform(-2e-3, 2e-3, (2, 200))
    z = rng.uniform(0.0, 2e-3, 200)
    loads = rng.normal(size=(3, 200))
    g = displacement_gradient(x, y, z, *loads, E_PA, nu)
    eps = 0.5 * (g + np.swapaxes(g, -1, -2))
    f = point_load_strain(x, y, z, *loads, E_PA, nu, chunk=37)
    for got, (i, j) in zip(f, [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]):
        np.testing.assert_allclose(got, eps[:, i, j], rtol=1e-9, atol=1e-12 * np.abs(eps).max())
