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
import numpy as np


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
