"""Mean vertical stress over a buried round sensing disc under a round load on the surface.

A load of contact radius a on an elastic half-space, with a pressure profile over its disc
(uniform; a rigid flat punch p ~ 1/sqrt(1 - r^2/a^2), Johnson, *Contact Mechanics*, 1985,
eq. 3.35; Hertz p ~ sqrt(1 - r^2/a^2), eq. 4.23), gives at depth z Boussinesq's vertical stress
(`vertical_stress_pa` in data/physics/elastic_half_space.py) superposed over the load's disc;
a sensor (a capacitive crossing's fringing field) reads its mean over its own disc. Both discs
are round, so the mean stress per newton depends on the centre distance and the load's radius
alone: tabulated once per process (`stress_kernel`) and interpolated (`kernel_lookup`).
"""
from functools import lru_cache

import numpy as np

from data.physics.elastic_half_space import disc_quadrature, vertical_stress_pa

PROFILES = ("uniform", "punch", "hertz")


def profile_weights(profile: str, rings: int, points_per_ring: int) -> np.ndarray:
    """Share of the load on each node of disc_quadrature's equal-area rings, from the exact
    ring integrals of the pressure profile (uniform, flat punch, Hertz)."""
    edges = np.sqrt(np.arange(rings + 1) / rings)
    cumulative = {"uniform": edges**2, "punch": 1.0 - np.sqrt(1.0 - edges**2),
                  "hertz": 1.0 - (1.0 - edges**2) ** 1.5}[profile]
    return np.repeat(np.diff(cumulative) / points_per_ring, points_per_ring)


@lru_cache(maxsize=16)
def stress_kernel(depth_mm: float, sensing_radius_mm: float, profile: str, radius_step_mm: float = 0.25,
                  max_radius_mm: float = 15.0, distance_step_mm: float = 0.25):
    """Mean vertical stress per newton (Pa/N) over a crossing's sensing disc at `depth_mm`, as a
    table over the centre distance between load and crossing (rows) and the load's contact
    radius (columns). Both discs are round, so the mean depends on the distance alone. Beyond
    12 depths the Boussinesq stress (z/R)^5 has fallen below 1e-5 of its peak and is taken as zero."""
    distances = np.arange(0.0, 12.0 * depth_mm + distance_step_mm, distance_step_mm)
    radii = np.arange(0.0, max_radius_mm + radius_step_mm, radius_step_mm)
    rx_x, rx_y, rx_w = disc_quadrature(sensing_radius_mm * 1e-3, rings=3, points_per_ring=8)
    table = np.empty((len(distances), len(radii)))
    for j, radius in enumerate(radii):
        src_x, src_y, _ = disc_quadrature(radius * 1e-3, rings=4, points_per_ring=8)
        src_w = profile_weights(profile, 4, 8) if radius > 0 else np.ones(1)
        dx = distances[:, None, None] * 1e-3 + rx_x[None, :, None] - src_x[None, None, :]
        dy = rx_y[None, :, None] - src_y[None, None, :]
        stress = vertical_stress_pa(dx, dy, depth_mm * 1e-3, 1.0)
        table[:, j] = np.einsum("drs,r,s->d", stress, rx_w, src_w)
    return distances, radii, table


def kernel_lookup(kernel, distance_mm: np.ndarray, radius_mm: np.ndarray) -> np.ndarray:
    """Bilinear interpolation in the stress table; zero beyond its last distance."""
    distances, radii, table = kernel
    fd = np.clip(distance_mm / distances[1], 0.0, len(distances) - 1.000001)
    fr = np.clip(radius_mm / radii[1], 0.0, len(radii) - 1.000001)
    i, j = fd.astype(np.int64), fr.astype(np.int64)
    u, v = fd - i, fr - j
    value = ((1 - u) * (1 - v) * table[i, j] + u * (1 - v) * table[i + 1, j]
             + (1 - u) * v * table[i, j + 1] + u * v * table[i + 1, j + 1])
    return np.where(distance_mm >= distances[-1], 0.0, value)
