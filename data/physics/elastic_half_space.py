"""Stress and strain inside an elastic half-space below point loads on its surface.

Coordinates: the surface is z = 0 and `depth_m` (z) points into the solid, towards the sensor
below the cover. (`dx_m`, `dy_m`, `depth_m`) is the field point measured FROM the load's point
of application, so a taxel at x_t under a load at x_l has dx_m = x_t - x_l. Strains are
tension-positive; tensor shear components (eps_xz = gamma_xz / 2) are returned alongside the
engineering shears.

Sources (displacements differentiated here by hand; checked against equilibrium, the
traction-free surface and the resultant force in tests/data/physics/test_elastic_half_space.py):
- Boussinesq (normal force P pressing into the solid): Johnson, *Contact Mechanics* (1985)
  eq. 3.19; Timoshenko & Goodier, *Theory of Elasticity* (1970) sec. 138:
      u_x = P/(4 pi G) [x z / R^3 - (1 - 2 nu) x / (R (R + z))]
      u_z = P/(4 pi G) [z^2 / R^3 + 2 (1 - nu) / R]
  and sigma_zz = -3 P z^3 / (2 pi R^5) (tension positive), independent of nu.
- Cerruti (tangential force Q along +x): Johnson (1985) eq. 3.20 (Love, *Mathematical Theory
  of Elasticity*, 1927, sec. 167):
      u_x = Q/(4 pi G) [1/R + x^2/R^3 + (1 - 2 nu)(1/(R + z) - x^2/(R (R + z)^2))]
      u_y = Q/(4 pi G) [x y / R^3 - (1 - 2 nu) x y / (R (R + z)^2)]
      u_z = Q/(4 pi G) [x z / R^3 + (1 - 2 nu) x / (R (R + z))]
  G = E / (2 (1 + nu)), R^2 = x^2 + y^2 + z^2.
  Written with R (R + z) instead of the textbook's r^2 (1 - z/R), these stay finite on the load's
  axis (r = 0) for every z > 0, and every (1 - 2 nu) term simply vanishes at nu = 0.5 (no 0/0).
- Seed 004 eq. (1) (nu = 0.5) is the special case: eps_z = 3 (Q x + F z)(x^2 + y^2 - 2 z^2) /
  (4 pi E R^5); its gamma_x, gamma_y equal -eps_xz, -eps_yz here (the paper's shear sign).

The singular point. A point load's field diverges as 1/R^2 at its own point of application,
where continuum elasticity (and the idea of a point load) stops holding. Rule used everywhere in
this module: a field point closer than `core_radius_m` (default 1 um, below any real needle tip)
to the load is moved straight down onto the sphere R = core_radius_m and evaluated there. The
result is continuous across that sphere, finite everywhere, and unchanged for R >= core_radius_m;
at the singular point itself sigma_zz = 3 P / (2 pi a^2) and eps_zz = -(3 - 2 nu) P (1 + nu) /
(2 pi E a^2), the values directly below the load at depth a.
"""
from typing import NamedTuple

import numpy as np

from common.errors import InputError

DEFAULT_CORE_RADIUS_M = 1.0e-6


class StrainField(NamedTuple):
    """Small-strain tensor components (tension positive) at the field points."""
    eps_xx: np.ndarray
    eps_yy: np.ndarray
    eps_zz: np.ndarray
    eps_xy: np.ndarray  # tensor shear = gamma_xy / 2
    eps_xz: np.ndarray
    eps_yz: np.ndarray

    @property
    def gamma_xz(self) -> np.ndarray:
        """Engineering shear strain 2 eps_xz."""
        return 2.0 * self.eps_xz

    @property
    def gamma_yz(self) -> np.ndarray:
        return 2.0 * self.eps_yz

    @property
    def gamma_xy(self) -> np.ndarray:
        return 2.0 * self.eps_xy


def check_material(youngs_modulus_pa, poisson_ratio) -> None:
    """One-line InputError for a modulus that is not positive or nu outside (0, 0.5]."""
    if not np.all(np.isfinite(youngs_modulus_pa)) or np.any(np.asarray(youngs_modulus_pa) <= 0):
        raise InputError(f"elastic half-space: Young's modulus must be > 0 Pa, got {youngs_modulus_pa}")
    nu = np.asarray(poisson_ratio, dtype=float)
    if not np.all(np.isfinite(nu)) or np.any(nu <= 0.0) or np.any(nu > 0.5):
        raise InputError(f"elastic half-space: Poisson ratio must be in (0, 0.5], got {poisson_ratio}")


def _regularised_geometry(dx_m, dy_m, depth_m, core_radius_m):
    """Broadcast the field points and apply the core rule (see module docstring)."""
    x, y, z = np.broadcast_arrays(np.asarray(dx_m, dtype=float), np.asarray(dy_m, dtype=float),
                                  np.asarray(depth_m, dtype=float))
    if np.any(z < 0.0):
        raise InputError("elastic half-space: depth_m must be >= 0 (points lie in or below the surface)")
    if not (core_radius_m > 0.0):
        raise InputError(f"elastic half-space: core_radius_m must be > 0, got {core_radius_m}")
    r2 = x * x + y * y
    a2 = core_radius_m * core_radius_m
    # Inside the core sphere, push the point down onto R = a: z = sqrt(a^2 - r^2).
    z = np.where(r2 + z * z < a2, np.sqrt(np.maximum(a2 - r2, 0.0)), z)
    rho = np.sqrt(r2 + z * z)
    return x, y, z, rho


def vertical_stress_pa(dx_m, dy_m, depth_m, normal_n, core_radius_m=DEFAULT_CORE_RADIUS_M):
    """Boussinesq sigma_zz below a normal point load, compressive positive, in pascals.

    sigma_zz = 3 P z^3 / (2 pi R^5) (Johnson 1985 eq. 3.18f), the same for every Poisson ratio.
    All arguments broadcast. Finite at the load point by the core rule in the module docstring
    (3 P / (2 pi a^2) there). Integrates to P over any horizontal plane z > 0.
    """
    x, y, z, rho = _regularised_geometry(dx_m, dy_m, depth_m, core_radius_m)
    return 3.0 * np.asarray(normal_n, dtype=float) * z**3 / (2.0 * np.pi * rho**5)


def _boussinesq_gradient(x, y, z, rho, nu):
    """Displacement gradient du_i/dx_j per unit 1/(4 pi G) of a unit normal load (tuple of 9)."""
    b = 1.0 - 2.0 * nu
    p3 = 1.0 / rho**3
    p5 = p3 / (rho * rho)
    s = rho + z
    q = 1.0 / (rho * s)                        # 1/(R (R+z))
    t = (2.0 * rho + z) / (rho**3 * s * s)     # -d q / d x_j = x_j t  (j = x, y)
    uxx = z * p3 - 3.0 * x * x * z * p5 - b * (q - x * x * t)
    uxy = -3.0 * x * y * z * p5 + b * x * y * t
    uxz = (1.0 + b) * x * p3 - 3.0 * x * z * z * p5
    uyx = uxy
    uyy = z * p3 - 3.0 * y * y * z * p5 - b * (q - y * y * t)
    uyz = (1.0 + b) * y * p3 - 3.0 * y * z * z * p5
    uzx = -3.0 * x * z * z * p5 - 2.0 * (1.0 - nu) * x * p3
    uzy = -3.0 * y * z * z * p5 - 2.0 * (1.0 - nu) * y * p3
    uzz = 2.0 * nu * z * p3 - 3.0 * z**3 * p5
    return uxx, uxy, uxz, uyx, uyy, uyz, uzx, uzy, uzz


def _cerruti_gradient(a, c, z, rho, nu):
    """Gradient of the Cerruti field of a unit load along coordinate `a` (c transverse), per 1/(4 pi G).

    Returned in the (a, c, z) frame: (u_aa, u_ac, u_az, u_ca, u_cc, u_cz, u_za, u_zc, u_zz).
    """
    b = 1.0 - 2.0 * nu
    p3 = 1.0 / rho**3
    p5 = p3 / (rho * rho)
    s = rho + z
    q = 1.0 / (rho * s)                        # 1/(R (R+z))
    q2 = q / s                                 # 1/(R (R+z)^2)
    t = (2.0 * rho + z) / (rho**3 * s * s)     # -dq/da / a
    w = (s + 2.0 * rho) / (rho**3 * s**3)      # -dq2/da / a
    vz = (z + 2.0 * rho) / (rho**3 * s * s)    # -dq2/dz
    uaa = a * p3 - 3.0 * a**3 * p5 + b * (-3.0 * a * q2 + a**3 * w)
    uac = -c * p3 - 3.0 * a * a * c * p5 + b * (-c * q2 + a * a * c * w)
    uaz = -z * p3 - 3.0 * a * a * z * p5 + b * (-q + a * a * vz)
    uca = c * p3 - 3.0 * a * a * c * p5 - b * (c * q2 - a * a * c * w)
    ucc = a * p3 - 3.0 * a * c * c * p5 - b * (a * q2 - a * c * c * w)
    ucz = -3.0 * a * c * z * p5 + b * a * c * vz
    uza = z * p3 - 3.0 * a * a * z * p5 + b * (q - a * a * t)
    uzc = -3.0 * a * c * z * p5 - b * a * c * t
    uzz = a * p3 - 3.0 * a * z * z * p5 - b * a * p3
    return uaa, uac, uaz, uca, ucc, ucz, uza, uzc, uzz


def displacement_gradient(dx_m, dy_m, depth_m, normal_n, shear_x_n, shear_y_n,
                          youngs_modulus_pa, poisson_ratio, core_radius_m=DEFAULT_CORE_RADIUS_M):
    """du_i/dx_j (i, j in x, y, z) for a point load (normal, shear_x, shear_y) in newtons.

    Returns an array of shape broadcast_shape + (3, 3). Superposes Boussinesq and two Cerruti
    fields (Johnson 1985 eq. 3.19-3.20); all arguments broadcast against each other.
    """
    check_material(youngs_modulus_pa, poisson_ratio)
    x, y, z, rho = _regularised_geometry(dx_m, dy_m, depth_m, core_radius_m)
    nu = np.asarray(poisson_ratio, dtype=float)
    scale = (1.0 + nu) / (2.0 * np.pi * np.asarray(youngs_modulus_pa, dtype=float))  # 1/(4 pi G)
    P = np.asarray(normal_n, dtype=float)
    Qx = np.asarray(shear_x_n, dtype=float)
    Qy = np.asarray(shear_y_n, dtype=float)
    gb = _boussinesq_gradient(x, y, z, rho, nu)
    gx = _cerruti_gradient(x, y, z, rho, nu)
    # Load along y: a = y, c = x; map (a, c, z) back to (x, y, z).
    yy, yx, yz, xy, xx, xz, zy, zx, zz = _cerruti_gradient(y, x, z, rho, nu)
    gy = (xx, xy, xz, yx, yy, yz, zx, zy, zz)
    comps = [scale * (P * b_ + Qx * cx + Qy * cy) for b_, cx, cy in zip(gb, gx, gy)]
    shape = np.broadcast_shapes(*(c.shape for c in comps))
    return np.stack([np.broadcast_to(c, shape) for c in comps], axis=-1).reshape(shape + (3, 3))


def point_load_strain(dx_m, dy_m, depth_m, normal_n, shear_x_n, shear_y_n,
                      youngs_modulus_pa, poisson_ratio, core_radius_m=DEFAULT_CORE_RADIUS_M,
                      chunk: int = 16384) -> StrainField:
    """Small-strain tensor below a point load with normal (pressing) and shear components.

    Boussinesq + Cerruti for any nu in (0, 0.5] (InputError otherwise, and for depth < 0 or
    E <= 0). All arguments broadcast: e.g. loads of shape (n, 1) against taxels of shape (1, m)
    give (n, m) fields. Finite everywhere by the core rule in the module docstring.

    The displacement gradients of `displacement_gradient` collapse, summed, into closed forms
    with L = P z + Q_x x + Q_y y (seed 004 eq. 1's "Qx + Fz"), per 1/(4 pi G):
        eps_xz = -3 x z L / R^5,  eps_yz = -3 y z L / R^5,  eps_zz = L (2 nu R^2 - 3 z^2) / R^5,
        eps_xx = L (R^2 - 3 x^2) / R^5 + (1 - 2 nu) B_xx, ... (B: the terms in 1/(R (R + z))),
    so the shears do not depend on nu and the (1 - 2 nu) part is skipped at nu = 0.5. Evaluated
    in chunks of `chunk` points so the temporaries stay in cache (tests check against the
    gradient form).
    """
    check_material(youngs_modulus_pa, poisson_ratio)
    if not (core_radius_m > 0.0):
        raise InputError(f"elastic half-space: core_radius_m must be > 0, got {core_radius_m}")
    arrays = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (
        dx_m, dy_m, depth_m, normal_n, shear_x_n, shear_y_n, youngs_modulus_pa, poisson_ratio)))
    shape = arrays[0].shape
    if np.any(arrays[2] < 0.0):
        raise InputError("elastic half-space: depth_m must be >= 0 (points lie in or below the surface)")
    flat = [a.reshape(-1) for a in arrays]
    uniform_nu = np.all(flat[7] == flat[7].flat[0]) if flat[7].size else True
    out = np.empty((6, flat[0].size))
    a2 = core_radius_m * core_radius_m
    for start in range(0, flat[0].size, chunk):
        part = slice(start, start + chunk)
        x, y, z, p, qx, qy, e, nu = (a[part] for a in flat)
        r2 = x * x + y * y
        inside = r2 + z * z < a2
        if inside.any():  # the core rule: push points inside R < a down onto the sphere R = a
            z = np.where(inside, np.sqrt(np.maximum(a2 - r2, 0.0)), z)
        rho2 = r2 + z * z
        rho = np.sqrt(rho2)
        scale = (1.0 + nu) / (2.0 * np.pi * e)            # 1/(4 pi G)
        load = p * z + qx * x + qy * y
        p5 = scale * load / (rho2 * rho2 * rho)            # A L / R^5
        out[0, part] = p5 * (rho2 - 3.0 * x * x)
        out[1, part] = p5 * (rho2 - 3.0 * y * y)
        out[2, part] = p5 * (2.0 * nu * rho2 - 3.0 * z * z)
        out[3, part] = -3.0 * x * y * p5
        out[4, part] = -3.0 * x * z * p5
        out[5, part] = -3.0 * y * z * p5
        if not (uniform_nu and nu[0] == 0.5):
            b = scale * (1.0 - 2.0 * nu)
            s = rho + z
            q = 1.0 / (rho * s)                            # 1/(R (R+z))
            q2 = q / s                                     # 1/(R (R+z)^2)
            t = (2.0 * rho + z) * q2 / rho2                # (2R + z) / (R^3 (R+z)^2)
            w = (s + 2.0 * rho) * q2 / (rho2 * s)          # (R+z + 2R) / (R^3 (R+z)^3)
            out[0, part] += b * (-p * (q - x * x * t) + qx * (-3.0 * x * q2 + x**3 * w) - qy * y * (q2 - x * x * w))
            out[1, part] += b * (-p * (q - y * y * t) + qy * (-3.0 * y * q2 + y**3 * w) - qx * x * (q2 - y * y * w))
            out[3, part] += b * (p * x * y * t + qx * y * (x * x * w - q2) + qy * x * (y * y * w - q2))
    out = out.reshape((6,) + shape)
    return StrainField(eps_xx=out[0], eps_yy=out[1], eps_zz=out[2], eps_xy=out[3], eps_xz=out[4], eps_yz=out[5])


def disc_quadrature(radius_m: float, rings: int = 4, points_per_ring: int = 8):
    """Nodes (x, y) and area weights (summing to 1) covering a disc of radius `radius_m`.

    Equal-area rings, each sampled at its area-centroid radius and rotated half a step from the
    previous one. Used to superpose point-load fields under a finite contact (a needle tip, a
    fingertip): the field of a pressure p(x, y) is the weighted sum of point-load fields.
    """
    if radius_m < 0.0:
        raise InputError(f"disc quadrature: radius_m must be >= 0, got {radius_m}")
    if radius_m == 0.0:
        return np.zeros(1), np.zeros(1), np.ones(1)
    edges = radius_m * np.sqrt(np.arange(rings + 1) / rings)
    xs, ys = [], []
    for k in range(rings):
        r_mid = (2.0 / 3.0) * (edges[k + 1]**3 - edges[k]**3) / (edges[k + 1]**2 - edges[k]**2)
        angles = 2.0 * np.pi * (np.arange(points_per_ring) + 0.5 * (k % 2)) / points_per_ring
        xs.append(r_mid * np.cos(angles))
        ys.append(r_mid * np.sin(angles))
    x = np.concatenate(xs)
    y = np.concatenate(ys)
    return x, y, np.full(x.shape, 1.0 / x.size)


def distributed_load_strain(dx_m, dy_m, depth_m, normal_n, shear_x_n, shear_y_n,
                            youngs_modulus_pa, poisson_ratio, contact_radius_m,
                            pressure_profile="uniform", rings=4, points_per_ring=8) -> StrainField:
    """Strain under a load spread over a disc of radius `contact_radius_m`, by superposition.

    pressure_profile: "uniform" (a flat-ended needle), "hertz" (a sphere or fingertip, p ~
    sqrt(1 - r^2/a^2), Johnson 1985 eq. 4.23; weights renormalised so the total stays the load)
    or "punch" (a rigid flat punch, p ~ 1/sqrt(1 - r^2/a^2), Johnson eq. 3.35; its edge
    singularity is integrable and the ring weights carry it). The load's total normal and shear
    forces are split over the nodes with the profile's weights; the point-load fields are summed.
    """
    nodes_x, nodes_y, weights = disc_quadrature(contact_radius_m, rings, points_per_ring)
    if contact_radius_m > 0.0:
        edges = np.sqrt(np.arange(rings + 1) / rings)  # ring edges in units of a
        # Exact ring share of the profile's total force (closed forms of int p 2 pi r dr).
        if pressure_profile == "uniform":
            cumulative = edges**2
        elif pressure_profile == "hertz":
            cumulative = 1.0 - (1.0 - edges**2) ** 1.5
        elif pressure_profile == "punch":
            cumulative = 1.0 - np.sqrt(1.0 - edges**2)
        else:
            raise InputError(f"distributed load: unknown pressure_profile '{pressure_profile}'; "
                             "valid: uniform, hertz, punch")
        ring_share = np.diff(cumulative)
        weights = np.repeat(ring_share / points_per_ring, points_per_ring)
    dx = np.asarray(dx_m, dtype=float)[..., None] - nodes_x
    dy = np.asarray(dy_m, dtype=float)[..., None] - nodes_y
    z = np.asarray(depth_m, dtype=float)[..., None]
    field = point_load_strain(dx, dy, z,
                              np.asarray(normal_n, dtype=float)[..., None] * weights,
                              np.asarray(shear_x_n, dtype=float)[..., None] * weights,
                              np.asarray(shear_y_n, dtype=float)[..., None] * weights,
                              youngs_modulus_pa, poisson_ratio)
    return StrainField(*(component.sum(axis=-1) for component in field))
