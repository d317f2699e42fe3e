"""Incompressible rubber in uniaxial compression: the material laws of the soft layers.

- Neo-Hookean (Treloar, *The Physics of Rubber Elasticity*, 3rd ed. 1975, ch. 4-5; physics
  notes): nominal stress s = (E/3)(lambda^-2 - lambda) at stretch lambda = 1 - strain, G = E/3.
  Soft silicones at tens of percent strain need it: a linear law misses their stiffening.
- Gent (Gent, "A new constitutive relation for rubber", Rubber Chem. Technol. 69, 59, 1996):
  the neo-Hookean stress times J_m / (J_m - (I1 - 3)), I1 = lambda^2 + 2/lambda, a material
  that locks as I1 - 3 reaches J_m (a densifying foam or fabric spacer); J_m -> infinity is
  neo-Hookean.

Used by the rubber12 scene (the gel column's secant stiffening at a given strain) and the
capacitive6x6 scene (the spacer's stretch under a given stress).
"""
import numpy as np


def neo_hookean_stiffening(strain):
    """Secant stiffening of a neo-Hookean solid in uniaxial compression over its small-strain
    modulus: nominal stress (E/3)(lambda - lambda^-2), lambda = 1 - strain (Treloar, *The
    Physics of Rubber Elasticity*, 3rd ed. 1975, ch. 5; physics notes), divided by E * strain.
    1 at zero strain, 1.05 at 5 %, 1.17 at 15 %, 2.33 at 50 %."""
    e = np.clip(np.asarray(strain, dtype=float), 0.0, 0.95)
    stretch = 1.0 - e
    small = e < 1e-6
    ratio = (stretch**-2 - stretch) / (3.0 * np.where(small, 1.0, e))
    return np.where(small, 1.0, ratio)


def neo_hookean_stretch(stress_pa: np.ndarray, youngs_modulus_pa: float) -> np.ndarray:
    """Stretch lambda <= 1 of an incompressible neo-Hookean solid under a uniaxial compressive
    stress s >= 0: s = (E/3)(lambda^-2 - lambda) (Treloar, *The Physics of Rubber Elasticity*,
    1975, eq. 4.9 with G = E/3), i.e. lambda^3 + (3 s / E) lambda^2 - 1 = 0, solved by Newton's
    method from the small-strain guess (monotone and convergent for s >= 0)."""
    stress_pa = np.asarray(stress_pa, dtype=float)
    stretch = np.ones(stress_pa.shape)
    loaded = stress_pa > 0          # rest frames and crossings out of a load's reach: nothing to solve
    k = 3.0 * stress_pa[loaded] / youngs_modulus_pa
    value = 1.0 / (1.0 + k / 3.0)
    for _ in range(50):  # quadratic convergence: ~5 steps to 1e-13 from this guess
        square = value * value
        f = square * (value + k) - 1.0
        value = value - f / (value * (3.0 * value + 2.0 * k))
        if not np.any(np.abs(f) > 1e-13):
            break
    stretch[loaded] = value
    return stretch


def gent_stretch(stress_pa: np.ndarray, youngs_modulus_pa: float, limiting_i1: float) -> np.ndarray:
    """Stretch lambda <= 1 of an incompressible Gent solid under a uniaxial compressive stress
    s >= 0: s = (E/3)(lambda^-2 - lambda) J_m / (J_m - (I1 - 3)), I1 = lambda^2 + 2/lambda
    (Gent, "A new constitutive relation for rubber", Rubber Chem. Technol. 69, 59, 1996). The
    neo-Hookean law times a factor that grows without bound as I1 - 3 reaches the limiting value
    J_m (`limiting_i1`): the material stiffens as it closes, and J_m -> infinity is neo-Hookean.

    Between the locking stretch (I1 - 3 = J_m) and 1 the stress is a positive, decreasing,
    convex function of lambda (a product of two such factors), so Newton's method started left
    of the root rises monotonically onto it. The neo-Hookean stretch is left of it (Gent is
    stiffer), unless it lies beyond the locking stretch, where the start is just inside it."""
    stress_pa = np.asarray(stress_pa, dtype=float)
    stretch = np.ones(stress_pa.shape)
    loaded = stress_pa > 0
    s, g = stress_pa[loaded], youngs_modulus_pa / 3.0
    # the locking stretch: I1 - 3 = J_m on lambda < 1, where I1 - 3 falls monotonically in lambda
    low, high = 1e-6, 1.0
    for _ in range(60):
        middle = 0.5 * (low + high)
        low, high = (low, middle) if middle * middle + 2.0 / middle - 3.0 < limiting_i1 else (middle, high)
    locking = high
    value = np.maximum(neo_hookean_stretch(s, youngs_modulus_pa), locking + 1e-9 * (1.0 - locking))
    for _ in range(200):  # a few steps from the neo-Hookean start; ~40 from just inside the lock
        room = limiting_i1 - (value * value + 2.0 / value - 3.0)
        neo = g * (1.0 / (value * value) - value)
        f = neo * limiting_i1 / room - s
        slope = (g * (-2.0 / value**3 - 1.0) * limiting_i1 / room
                 + neo * limiting_i1 * (2.0 * value - 2.0 / (value * value)) / (room * room))
        step = -f / slope
        value = np.minimum(value + step, 1.0)
        if not np.any(np.abs(step) > 1e-14):
            break
    stretch[loaded] = value
    return stretch
