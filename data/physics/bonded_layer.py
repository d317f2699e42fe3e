"""The field at a rigid base under an elastic layer on it, from point loads on the layer's surface.

The problem: a layer of thickness h (the taxels' rubber cover) on a rigid base (the silicon chip:
170 GPa against 2.4 MPa), loaded at its free surface by a point force with a normal component P
(pressing) and a tangential component Q. The base is either bonded (welded: u = 0 at z = h) or
frictionless (lubricated: w = 0 and no shear traction at z = h), the two standard idealisations
of a layer on a rigid foundation (Burmister 1945; Sneddon 1951 ch. 10). Returned at z = h: the
traction the layer exerts on the chip, (sigma_xz, sigma_yz, sigma_zz), the rubber's normal strain
eps_zz and its gradient d eps_zz / dz (the strain a small height above the chip, to first order).
At a rigid bonded face the rubber cannot stretch, u = 0, so eps_xx = eps_yy = 0 and, incompressible,
eps_zz = 0 too; just above it eps_zz = d div(tau) / G (tau the base shear traction). A frictionless
base carries no net shear force, so a tangential load on it has no equilibrium (InputError).

Method: the Fourier-Hankel transform solution for layered elastic systems (Burmister, J. Appl.
Phys. 16 (1945) 89-94 and 296-302; Sneddon, *Fourier Transforms* (1951) ch. 10). In the 2-D
Fourier domain of the surface coordinates, a wave vector k (|k| = xi) splits the field into an
in-plane "P-SV" part, written with Love's strain function phi (Timoshenko & Goodier, *Theory of
Elasticity* (1970) sec. 135: 2G u = 2(1 - nu) lap(phi) e_z - grad(d phi / dz), lap^2 phi = 0;
sigma_zz = d/dz[(2 - nu) lap phi - phi_zz], sigma_rz = d/dr[(1 - nu) lap phi - phi_zz], all
regular at nu = 0.5) with Phi(z) = (A + B z) e^{-xi z} + (C + D (h - z)) e^{-xi (h - z)}, and
an anti-plane "SH" part G (u'' - xi^2 u) = 0. Four boundary conditions fix the P-SV constants for
each xi: the surface tractions (the load) at z = 0 and two at z = h (BASE_CONDITIONS); two fix the
SH part, whose base traction is -sech(xi h) when bonded. 2G eps_zz = d/dz[2 (1 - nu) lap phi -
phi_zz] is regular at nu = 0.5 as well. The base fields are brought back to real space by Hankel
transforms of order 0, 1 and 2 (the angular integrals of cos(m phi) e^{i k.x}; Sneddon ch. 2):

  normal load P:   sigma_zz = P/h^2 K_zz(r/h),   sigma_rz = P/h^2 K_rz(r/h) (radial)
  shear Q along x: sigma_zz = Q/h^2 K_zq(r/h) cos(theta),
                   sigma_xz = Q/h^2 [K_0(r/h) + K_2(r/h) cos(2 theta)], sigma_yz = Q/h^2 K_2 sin(2 theta)

The problem has no length but h, so these five kernels (and four for eps_zz and its gradient)
are computed once per Poisson ratio and base in dimensionless form (trapezoid rule in xi h on
[0, 40], where the kernels' transforms have decayed
by e^-40), tabulated on r/h in [0, 12] and interpolated; beyond 12 h they are taken as zero (the
share of the load carried there is under 0.5 %, see tests). The same machinery with the base
moved to infinity reproduces Boussinesq's and Cerruti's stresses at depth h (the test of the
transform and its signs, tests/data/scenes/test_taxels.py).
"""
from functools import lru_cache

import numpy as np
from scipy.special import j0, j1

from common.errors import InputError
from data.physics.elastic_half_space import check_material

XI_MAX = 40.0       # in units of 1/h
XI_STEP = 0.01
R_MAX = 12.0        # in units of h
R_STEP = 0.01


def _phi_derivatives(xi, z, h, base):
    """Phi and its first four z-derivatives for each basis function: shape (n_xi, 5 orders, n_basis)."""
    s = -xi[:, None]
    decaying = np.exp(-xi * z)[:, None]
    order = np.arange(5)[None, :]
    columns = [s**order * decaying,                                           # e^{-xi z}
               (order * s ** np.maximum(order - 1, 0) * (order > 0) + s**order * z) * decaying]  # z e^{-xi z}
    if base != "half_space":  # a layer: the field reflected by the base too
        t = xi[:, None]
        growing = np.exp(-xi * (h - z))[:, None]                              # e^{-xi (h - z)}
        columns += [t**order * growing,
                    -(order * t ** np.maximum(order - 1, 0) * (order > 0) + t**order * (z - h)) * growing]
    return np.stack(columns, axis=-1)


def _field_rows(derivatives, xi, nu):
    """Transforms of u_L, u_z (times 2G), sigma_zz, sigma_Lz, 2G eps_zz and its z-derivative per basis
    function (plane wave e^{i xi x})."""
    phi1, phi2, phi3, phi4 = derivatives[:, 1], derivatives[:, 2], derivatives[:, 3], derivatives[:, 4]
    x2 = (xi * xi)[:, None]
    lap = phi2 - x2 * derivatives[:, 0]
    lap1 = phi3 - x2 * phi1
    u_l = -1j * xi[:, None] * phi1
    u_z = 2.0 * (1.0 - nu) * lap - phi2
    s_zz = (2.0 - nu) * lap1 - phi3
    s_lz = 1j * xi[:, None] * ((1.0 - nu) * lap - phi2)
    e_zz = 2.0 * (1.0 - nu) * lap1 - phi3          # d(2G u_z)/dz
    de_zz = 2.0 * (1.0 - nu) * (phi4 - x2 * phi2) - phi4
    return u_l, u_z, s_zz, s_lz, e_zz, de_zz


# The conditions at the base z = h, as rows of _field_rows (u_L, u_z, sigma_zz, sigma_Lz, eps_zz):
# bonded (welded) to a rigid base: u_L = u_z = 0; frictionless (lubricated) rigid base: u_z = 0 and
# sigma_Lz = 0 (Sneddon 1951 ch. 10; Burmister 1945 treats both as "continuous" and "frictionless"
# interfaces); half_space: no base (the field at depth z = h inside a half-space, for validation).
BASE_CONDITIONS = {"bonded": (0, 1), "frictionless": (1, 3), "half_space": ()}


def base_transfer(xi, poisson_ratio, depth=1.0, base="bonded"):
    """Fourier-domain field at z = depth per unit surface traction, for each xi (1-D array).

    Returns a dict: "zz_from_p", "lz_from_p", "ezz_from_p" (normal load: sigma_zz, sigma_Lz and
    2G eps_zz at depth), the same "_from_q" (load along the wave vector) and "tz_from_t" (sigma_Tz,
    load across it). base: a key of BASE_CONDITIONS. A frictionless base carries no tangential
    load at all (no shear traction: a net shear force has no equilibrium, the layer slides), so
    there only the normal-load entries are returned.
    """
    xi = np.asarray(xi, dtype=float)
    nu = float(poisson_ratio)
    top = _field_rows(_phi_derivatives(xi, 0.0, depth, base), xi, nu)
    at = _field_rows(_phi_derivatives(xi, depth, depth, base), xi, nu)
    conditions = [top[2], top[3]] + [at[row] for row in BASE_CONDITIONS[base]]
    matrix = np.stack(conditions, axis=-2).astype(complex)
    zeros = (0.0,) * len(BASE_CONDITIONS[base])
    out = {}
    loads = (("p", (-1.0, 0.0)),) + ((("q", (0.0, -1.0)),) if base != "frictionless" else ())
    for name, rhs in loads:  # sigma_iz(0) = -applied traction
        rhs = np.array(rhs + zeros, dtype=complex)
        coefficients = np.linalg.solve(matrix, np.broadcast_to(rhs, xi.shape + rhs.shape)[..., None])[..., 0]
        out[f"zz_from_{name}"] = (at[2] * coefficients).sum(-1)
        out[f"lz_from_{name}"] = (at[3] * coefficients).sum(-1)
        out[f"ezz_from_{name}"] = (at[4] * coefficients).sum(-1)
        out[f"dezz_from_{name}"] = (at[5] * coefficients).sum(-1)
    # SH: u = a e^{-xi z} + b e^{-xi (h - z)}, u(h) = 0 (bonded), G u'(0) = -1.
    if base == "bonded":
        out["tz_from_t"] = -1.0 / np.cosh(xi * depth)
    elif base == "half_space":
        out["tz_from_t"] = -np.exp(-xi * depth)
    return out


def _hankel(transforms, order, r, xi, weights):
    """(1 / 2 pi) int_0^inf transform(xi) J_order(xi r) xi d xi for each row of `transforms`
    (k, n_xi), by the trapezoid rule, chunked over r (one Bessel table per order and chunk)."""
    transforms = np.atleast_2d(transforms) * weights
    out = np.empty((transforms.shape[0], r.size))
    for start in range(0, r.size, 200):
        part = slice(start, start + 200)
        argument = np.outer(r[part], xi)
        if order == 2:  # J2 = 2 J1(x) / x - J0(x) (DLMF 10.6.1), J2(0) = 0; cheaper than jv
            safe = np.where(argument > 0.0, argument, 1.0)
            bessel = np.where(argument > 0.0, 2.0 * j1(safe) / safe - j0(argument), 0.0)
        else:
            bessel = (j0 if order == 0 else j1)(argument)
        out[:, part] = transforms @ bessel.T
    return out / (2.0 * np.pi)


KERNELS = ("zz", "rz", "zq", "q0", "q2", "ez", "ezq", "dp", "dq")


@lru_cache(maxsize=8)
def layer_kernels(poisson_ratio: float, base: str = "bonded"):
    """Dimensionless kernels (see module docstring) on the grid r/h = 0, R_STEP, ..., R_MAX.

    Besides the five traction kernels: "ez", "ezq" (2G eps_zz at the base from P and from Q,
    as zz and zq) and "dp", "dq" (its gradient d(2G eps_zz)/dz at the base, per P/h^3 and Q/h^3:
    order 0 and order 1 cos(theta); at nu = 0.5 on a bonded base it is -2 div(tau), tau the base
    shear traction, by incompressibility). On a frictionless base the shear-load kernels are
    zero: that base cannot carry a tangential load. Cached per (Poisson ratio, base): about
    1.5 s the first time in a process.
    """
    if base not in BASE_CONDITIONS:
        raise InputError(f"elastic layer: base must be one of {', '.join(BASE_CONDITIONS)}, got '{base}'")
    xi = np.arange(0.0, XI_MAX + XI_STEP / 2, XI_STEP)
    xi[0] = 1e-9  # the transforms are finite at xi = 0; the solve needs xi > 0
    weights = xi * XI_STEP
    weights[0] *= 0.5
    weights[-1] *= 0.5
    r = np.arange(0.0, R_MAX + R_STEP / 2, R_STEP)
    n = base_transfer(xi, poisson_ratio, 1.0, base)
    # Angular integrals (Sneddon 1951 ch. 2): int cos(phi) e^{i xi r cos(phi - theta)} dphi =
    # 2 pi i J1 cos(theta); int cos(2 phi) ... = -2 pi J2 cos(2 theta). The P-SV cross terms are
    # imaginary (odd in x), so i * (i Im N) = -Im N.
    has_shear = "zz_from_q" in n   # a frictionless base carries no shear load: those kernels stay 0
    zero = np.zeros(xi.shape)
    q = {key: n[key] if has_shear else zero for key in ("zz_from_q", "lz_from_q", "ezz_from_q", "dezz_from_q")}
    tz = n.get("tz_from_t", zero)
    order0 = _hankel([n["zz_from_p"].real, n["ezz_from_p"].real, n["dezz_from_p"].real,
                      0.5 * (q["lz_from_q"].real + tz)], 0, r, xi, weights)
    order1 = -_hankel([n["lz_from_p"].imag, q["zz_from_q"].imag, q["ezz_from_q"].imag, q["dezz_from_q"].imag],
                      1, r, xi, weights)
    order2 = -_hankel([0.5 * (q["lz_from_q"].real - tz)], 2, r, xi, weights)
    kernels = dict(zip(("zz", "ez", "dp", "q0"), order0)) | dict(zip(("rz", "zq", "ezq", "dq"), order1))
    kernels["q2"] = order2[0]
    return r, kernels


@lru_cache(maxsize=8)
def _kernel_table(poisson_ratio: float, base: str):
    """(9, n_grid + 2) table of KERNELS: two zero columns past R_MAX, so beyond it they read 0."""
    grid, k = layer_kernels(poisson_ratio, base)
    table = np.zeros((len(KERNELS), grid.size + 2))
    for row, name in enumerate(KERNELS):
        table[row, :grid.size] = k[name]
    return table


def base_field(dx_m, dy_m, thickness_m, normal_n, shear_x_n, shear_y_n, poisson_ratio=0.5,
               base="bonded", with_strain: bool = True, chunk: int = 16384) -> dict:
    """The field at the base below a layer, from point loads on its surface.

    Returns a dict of arrays (broadcast shape): "sigma_xz", "sigma_yz", "sigma_zz" (Pa, tension
    positive: the rubber's stress at z = h), "eps_zz_2g" (2G eps_zz, Pa: the rubber's normal
    strain at the base; zero on a bonded base at nu = 0.5) and "d_eps_zz_2g_dz" (its gradient
    along z, Pa/m: eps_zz a small height d above the base is (eps_zz_2g - d * d_eps_zz_2g_dz) / 2G).
    (dx_m, dy_m): the base point relative to the load; all arguments broadcast (loads x
    taxels); thickness_m > 0 and nu in (0, 0.5] (InputError otherwise); a frictionless base with
    a tangential load is an InputError (no equilibrium). Exact at the load's axis: the kernels are
    smooth there, so unlike the half-space surface there is no singular point. Linear
    interpolation on the uniform r/h grid, in chunks of `chunk` points (cache-sized temporaries);
    with_strain=False leaves out the two strain entries (about twice as fast).
    """
    check_material(1.0, poisson_ratio)
    if base not in BASE_CONDITIONS:
        raise InputError(f"elastic layer: base must be one of {', '.join(BASE_CONDITIONS)}, got '{base}'")
    arrays = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (
        dx_m, dy_m, thickness_m, normal_n, shear_x_n, shear_y_n)))
    h_all = arrays[2]
    if not np.all(np.isfinite(h_all)) or np.any(h_all <= 0.0):
        raise InputError(f"elastic layer: thickness must be > 0 m, got {np.min(h_all)}")
    if base == "frictionless" and (np.any(arrays[4] != 0.0) or np.any(arrays[5] != 0.0)):
        raise InputError("elastic layer: a frictionless base cannot carry a shear load (the layer would slide)")
    table = _kernel_table(float(poisson_ratio), base)
    table = table if with_strain else table[:5]
    shape = arrays[0].shape
    flat = [a.reshape(-1) for a in arrays]
    out = np.empty((len(table), flat[0].size))
    last = table.shape[1] - 3
    for start in range(0, flat[0].size, chunk):
        part = slice(start, start + chunk)
        x, y, h, p, qx, qy = (a[part] for a in flat)
        inverse_h = 1.0 / h
        x = x * inverse_h
        y = y * inverse_h
        r = np.sqrt(x * x + y * y)
        position = np.minimum(r * (1.0 / R_STEP), last + 1.0)
        index = position.astype(np.intp)
        fraction = position - index
        kernels = table[:, index] * (1.0 - fraction) + table[:, index + 1] * fraction
        zz, rz, zq, q0, q2 = kernels[:5]
        safe = np.where(r > 0.0, r, 1.0)
        cos_t = np.where(r > 0.0, x / safe, 1.0)
        sin_t = np.where(r > 0.0, y / safe, 0.0)
        cos_2t, sin_2t = cos_t * cos_t - sin_t * sin_t, 2.0 * sin_t * cos_t
        scale = inverse_h * inverse_h
        p, qx, qy = p * scale, qx * scale, qy * scale
        along = qx * cos_t + qy * sin_t           # shear along y = the x-kernels turned by 90 degrees
        out[2, part] = p * zz + zq * along
        out[0, part] = p * rz * cos_t + qx * (q0 + q2 * cos_2t) + qy * q2 * sin_2t
        out[1, part] = p * rz * sin_t + qx * q2 * sin_2t + qy * (q0 - q2 * cos_2t)
        if with_strain:
            ez, ezq, dp, dq = kernels[5:]
            out[3, part] = p * ez + ezq * along
            out[4, part] = (p * dp + dq * along) * inverse_h
    out = out.reshape((len(table),) + shape)
    return dict(zip(("sigma_xz", "sigma_yz", "sigma_zz", "eps_zz_2g", "d_eps_zz_2g_dz"), out))


def base_traction_pa(dx_m, dy_m, thickness_m, normal_n, shear_x_n, shear_y_n, poisson_ratio=0.5,
                     base="bonded", chunk: int = 16384):
    """Tractions (sigma_xz, sigma_yz, sigma_zz) in Pa, tension positive, on the rigid base below a
    layer (base_field's first three entries; same arguments)."""
    field = base_field(dx_m, dy_m, thickness_m, normal_n, shear_x_n, shear_y_n, poisson_ratio, base, False, chunk)
    return field["sigma_xz"], field["sigma_yz"], field["sigma_zz"]
