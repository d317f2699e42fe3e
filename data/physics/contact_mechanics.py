"""Contact mechanics of a flat cylindrical punch pressed into a soft elastic layer.

Sources:
- Sneddon, Int. J. Eng. Sci. 3 (1965) 47-57, and Johnson, *Contact Mechanics* (1985) sec. 3.8:
  on an elastic half-space a rigid flat punch of radius a pushed to depth d needs
  F = 2 a E* d with E* = E / (1 - nu^2), and the free surface outside the punch sinks by
  u_z(r) = (2 d / pi) * arcsin(a / r)   for r > a   (u_z = d under the punch).
- Shull, Mater. Sci. Eng. R 36 (2002) 1-45: a bonded layer of thickness h is stiffer than the
  half-space; for a flat punch the force grows by roughly 1 + 1.33 (a/h) + 1.33 (a/h)^3.
  This fit is approximate (physics notes mark it "verify"), so it is switchable.
"""
from functools import lru_cache

import numpy as np
from scipy.special import j0


def effective_modulus_pa(youngs_modulus_pa: float, poisson_ratio: float) -> float:
    """E* = E / (1 - nu^2): the plane-strain modulus of the gel against a rigid probe."""
    return youngs_modulus_pa / (1.0 - poisson_ratio**2)


def thin_layer_factor(radius_mm: float, thickness_mm: float) -> float:
    """Shull (2002) stiffening of a bonded layer under a flat punch: 1 + 1.33 r + 1.33 r^3, r = a/h."""
    ratio = radius_mm / thickness_mm
    return 1.0 + 1.33 * ratio + 1.33 * ratio**3


def flat_punch_force_n(depth_mm, radius_mm, youngs_modulus_pa, poisson_ratio=0.5,
                       thickness_mm=None):
    """Load-cell force in newtons for an indentation `depth_mm` (array-like).

    F = 2 a E* d (Sneddon), times the thin-layer factor when `thickness_mm` is given.
    Linear in depth either way: the layer correction depends on geometry, not depth.
    """
    depth_m = np.asarray(depth_mm, dtype=float) * 1e-3
    force = 2.0 * (radius_mm * 1e-3) * effective_modulus_pa(youngs_modulus_pa, poisson_ratio) * depth_m
    if thickness_mm is not None:
        force = force * thin_layer_factor(radius_mm, thickness_mm)
    return force


def mean_pressure_pa(force_n, radius_mm):
    """Mean contact pressure under the punch, P = F / (pi a^2), in pascals."""
    return np.asarray(force_n, dtype=float) / (np.pi * (radius_mm * 1e-3) ** 2)


def surface_deflection_mm(distance_mm, depth_mm, radius_mm):
    """Sneddon's surface profile around a flat punch: d inside, (2d/pi) asin(a/r) outside.

    `distance_mm` and `depth_mm` broadcast; the result is continuous at r = a.
    """
    r = np.asarray(distance_mm, dtype=float)
    d = np.asarray(depth_mm, dtype=float)
    outside = (2.0 / np.pi) * np.arcsin(np.minimum(1.0, radius_mm / np.maximum(r, 1e-12)))
    return d * np.where(r <= radius_mm, 1.0, outside)


# -- a flat punch on a gel bonded to a rigid base ----------------------------------------------
def bonded_incompressible_layer_factor(xi_h):
    """Surface compliance of an incompressible layer (nu = 0.5) of thickness h bonded to a rigid
    base, relative to the half-space's, for a surface pressure wave of wavenumber xi:

        u_z(xi) = p(xi) / (2 G xi) * K(xi h),   K(t) = (sinh 2t - 2t) / (cosh 2t + 2t^2 + 1).

    This is Burmister's layered solution (J. Appl. Phys. 16 (1945) 89-94) at nu = 0.5 with a
    welded base, the same Love-function construction as data/physics/bonded_layer.py. Its two
    limits are checked in tests: K -> 1 for a thick layer (the half-space, u_z = p / (2 G xi)),
    and K -> (2/3) t^3 for a thin one, i.e. u_z = h^3 xi^2 p / (3 G), the lubrication limit of
    a thin incompressible bonded layer (squeeze flow). Written with e^{-2t} so it never overflows.
    """
    t = np.asarray(xi_h, dtype=float)
    e2 = np.exp(-2.0 * t)
    e4 = e2 * e2
    return ((1.0 - e4) - 4.0 * t * e2) / ((1.0 + e4) + (4.0 * t * t + 2.0) * e2)


@lru_cache(maxsize=8)
def _bonded_layer_profile(radius_mm: float, thickness_mm: float):
    """Tabulated w(r) / w_mean for a flat punch on the bonded incompressible layer, r in mm, and
    the layer's stiffening over the half-space. See `bonded_layer_deflection_mm`."""
    a, h = radius_mm, thickness_mm
    xi = np.arange(0.0, 30.0, 0.01) / h        # per mm; K - 1 has decayed as e^-60 by 30 / h
    r = np.linspace(0.0, a + 8.0 * h, 801)
    # u_z(r) = F / (4 pi a G) [ H(r) + int_0^inf sin(xi a)/xi (K(xi h) - 1) J0(xi r) dxi ]
    # for Sneddon's punch pressure p = F / (2 pi a sqrt(a^2 - r^2)), whose Hankel transform is
    # F sin(xi a) / (2 pi a xi); H(r) is the half-space integral, pi/2 under the punch and
    # asin(a/r) outside (Sneddon 1965). Only K - 1 needs quadrature: it decays exponentially.
    correction = np.trapezoid((a * np.sinc(xi * a / np.pi) * (bonded_incompressible_layer_factor(xi * h) - 1.0))[None, :]
                              * j0(np.outer(r, xi)), xi, axis=1)
    half_space = np.where(r <= a, np.pi / 2, np.arcsin(np.minimum(1.0, a / np.maximum(r, 1e-12))))
    w = half_space + correction
    inside = r <= a
    mean_inside = np.trapezoid((w * r)[inside], r[inside]) / np.trapezoid(r[inside], r[inside])
    return r, w / mean_inside, (np.pi / 2) / mean_inside


def bonded_layer_deflection_mm(distance_mm, depth_mm, radius_mm, thickness_mm):
    """Surface of a gel of thickness h bonded to a rigid base around a flat punch pushed to depth d.

    Burmister's layer compliance (`bonded_incompressible_layer_factor`) under Sneddon's punch
    pressure, scaled so the mean deflection under the punch is d; under the punch the surface
    is flat at d. Outside, the surface sinks only within about h/3 of the rim and then bulges
    slightly up (an incompressible layer on a rigid base must put the displaced volume
    somewhere), dying out within ~3 h: the deflection spreads over the gel's thickness, not
    over the half-space's slow 1/r tail. Beyond 8 h it is taken as zero. The pressure
    distribution is the half-space's, an approximation for the layer (it gives a stiffening of
    ~2.2 over the half-space at a/h = 0.58, against Shull's fit 2.04).
    """
    r_table, w_table, _ = _bonded_layer_profile(float(radius_mm), float(thickness_mm))
    r = np.asarray(distance_mm, dtype=float)
    w = np.where(r <= radius_mm, 1.0, np.interp(r, r_table, w_table, right=0.0))
    return np.asarray(depth_mm, dtype=float) * w


def bonded_layer_stiffening(radius_mm: float, thickness_mm: float) -> float:
    """Force on the bonded layer over the half-space's at equal mean punch depth (~2.2 at a/h = 0.58)."""
    return float(_bonded_layer_profile(float(radius_mm), float(thickness_mm))[2])


def standard_linear_solid_relaxation(time_s, relaxed_fraction, time_constant_s):
    """Stress relaxation function of a standard linear solid normalised to 1 at t = 0:
    G(t)/G(0) = 1 - f (1 - exp(-t / tau)) (Zener 1948; Findley, Lai & Onaran, *Creep and
    Relaxation of Nonlinear Viscoelastic Materials*, 1976, ch. 5). f = share of the instantaneous
    modulus that relaxes."""
    t = np.asarray(time_s, dtype=float)
    return 1.0 - relaxed_fraction * (1.0 - np.exp(-t / time_constant_s))
