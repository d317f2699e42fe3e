"""Real contact area of a soft skin on a randomly rough, self-affine surface (Persson's theory).

A board's surface is described by its height power spectrum C(q) (isotropic, q = |wave vector|),
the form most engineering and natural surfaces follow (Persson, Albohr, Tartaglino, Volokitin &
Tosatti, J. Phys.: Condens. Matter 17 (2005) R1, eq. 13; Persson, Tribol. Lett. 54 (2014) 99):

    C(q) = C0                        q_L <= q < q0   (roll-off: flat above the roll-off wavelength)
    C(q) = C0 (q / q0)^(-2 (1 + H))  q0  <= q <= q1  (self-affine, Hurst exponent 0 < H < 1)

with q0 = 2 pi / roll-off wavelength, q1 = 2 pi / the shortest wavelength the contact resolves,
q_L = q0 / 4 (the longest wavelength that still fits a pad a few roll-off lengths wide). The
moments of the spectrum give the rms height and the rms slope (Persson et al. 2005, eqs. 6-7):

    h_rms^2 = 2 pi Int q   C(q) dq,        h'_rms^2 = 2 pi Int q^3 C(q) dq.

C0 is set from the material's rms height. Persson's contact theory (J. Chem. Phys. 115 (2001)
3840, eqs. 26-28; the closed form in Persson et al. 2005, eq. 30, and Persson, Surf. Sci. Rep.
61 (2006) 201, sec. 2) gives the share of the nominal area in real contact at nominal pressure p0:

    A_real / A0 = erf( sqrt(2) p0 / (E* h'_rms) ),        1 / E* = sum_i (1 - nu_i^2) / E_i,

linear in p0 at light load (A_real ~ sqrt(8/pi) F / (E* h'_rms), the result Greenwood-Williamson
also gives, Greenwood & Williamson, Proc. R. Soc. A 295 (1966) 300) and saturating at full contact
once p0 reaches about E* h'_rms: a smooth, stiff-looking surface saturates at a light load, a rough
one stays linear over the whole range. The transferred triboelectric charge follows the real
contact area (contact electrification happens where the surfaces touch: Zou et al., Nat. Commun.
10 (2019) 1427 used liquid mercury exactly to make the contact complete).

`surface_profile` draws a 1-D line scan of such a surface (random phases, amplitudes from the
1-D spectrum; Persson et al. 2005, appendix A: C_1D(q) = Int C(sqrt(q^2 + q_y^2)) dq_y, computed
numerically) with unit rms: what a point on the skin sees while sliding at speed v is that
profile at x = v t, so its temporal spectrum is C_1D(2 pi f / v).
"""
from functools import lru_cache

import numpy as np
from scipy.special import erf

from common.errors import InputError

ROLL_OFF_SPAN = 4.0     # q0 / q_L: the spectrum is flat over two octaves below the roll-off


def check_roughness(rms_height_um, hurst_exponent, roll_off_mm, cutoff_mm, name="surface"):
    values = {"rms_height_um": rms_height_um, "roll_off_mm": roll_off_mm, "cutoff_mm": cutoff_mm}
    for key, value in values.items():
        if not np.isfinite(value) or value <= 0:
            raise InputError(f"{name}: {key} must be positive, got {value}")
    if not 0 < hurst_exponent < 1:
        raise InputError(f"{name}: hurst_exponent must lie in (0, 1), got {hurst_exponent}")
    if cutoff_mm >= roll_off_mm:
        raise InputError(f"{name}: the cutoff wavelength ({cutoff_mm} mm) must be shorter than the "
                         f"roll-off wavelength ({roll_off_mm} mm)")


def _spectrum_shape(q, q0, hurst):
    """C(q) / C0."""
    return np.where(q < q0, 1.0, (np.maximum(q, 1e-300) / q0) ** (-2.0 * (1.0 + hurst)))


def _moment(power, q0, q1, hurst):
    """2 pi Int q^power C(q)/C0 dq over [q0 / ROLL_OFF_SPAN, q1], in closed form."""
    q_low = q0 / ROLL_OFF_SPAN
    flat = (q0 ** (power + 1) - q_low ** (power + 1)) / (power + 1)
    exponent = power - 2.0 * (1.0 + hurst) + 1.0     # of q in the self-affine integrand's primitive
    tail = q0 ** (2.0 * (1.0 + hurst)) * (np.log(q1 / q0) if abs(exponent) < 1e-12
                                            else (q1 ** exponent - q0 ** exponent) / exponent)
    return 2.0 * np.pi * (flat + tail)


def rms_slope(rms_height_um, hurst_exponent, roll_off_mm, cutoff_mm) -> float:
    """h'_rms (dimensionless) of the surface whose rms height (over the resolved band) is given."""
    check_roughness(rms_height_um, hurst_exponent, roll_off_mm, cutoff_mm)
    q0, q1 = 2 * np.pi / (roll_off_mm * 1e-3), 2 * np.pi / (cutoff_mm * 1e-3)
    c0 = (rms_height_um * 1e-6) ** 2 / _moment(1, q0, q1, hurst_exponent)
    return float(np.sqrt(c0 * _moment(3, q0, q1, hurst_exponent)))


def contact_modulus_pa(*materials) -> float:
    """E* of a contact: 1/E* = sum (1 - nu^2)/E over the (youngs_modulus_pa, poisson_ratio) pairs."""
    compliance = 0.0
    for youngs_modulus_pa, poisson_ratio in materials:
        if not youngs_modulus_pa > 0:
            raise InputError(f"elastic modulus must be positive, got {youngs_modulus_pa} Pa")
        if not -1 < poisson_ratio <= 0.5:
            raise InputError(f"Poisson ratio must lie in (-1, 0.5], got {poisson_ratio}")
        compliance += (1 - poisson_ratio ** 2) / youngs_modulus_pa
    return 1.0 / compliance


def real_contact_fraction(nominal_pressure_pa, contact_modulus, slope_rms) -> np.ndarray:
    """Persson: A_real / A0 = erf(sqrt(2) p0 / (E* h'_rms)); 0 at zero or negative (no) load."""
    p0 = np.maximum(np.asarray(nominal_pressure_pa, dtype=np.float64), 0.0)
    return erf(np.sqrt(2.0) * p0 / (contact_modulus * slope_rms))


@lru_cache(maxsize=64)
def _line_scan_amplitude(n_fft, step_mm, hurst_exponent, roll_off_mm, cutoff_mm) -> np.ndarray:
    """sqrt of the 1-D spectrum C_1D(q) = Int C(sqrt(q^2 + q_y^2)) dq_y on the rfft grid, zero
    outside [q_L, q1]; the shape only (the profile is normalised afterwards)."""
    q = 2 * np.pi * np.fft.rfftfreq(n_fft, step_mm * 1e-3)                 # 1/m
    q0, q1 = 2 * np.pi / (roll_off_mm * 1e-3), 2 * np.pi / (cutoff_mm * 1e-3)
    qy = q0 / ROLL_OFF_SPAN * np.geomspace(1e-3, 1e4, 96)
    c1d = np.trapezoid(_spectrum_shape(np.hypot(q[:, None], qy[None, :]), q0, hurst_exponent), qy, axis=1)
    band = (q >= q0 / ROLL_OFF_SPAN) & (q <= q1)
    amplitude = np.sqrt(np.where(band, c1d, 0.0))
    amplitude.flags.writeable = False
    return amplitude


def contact_pressure_sensitivity(nominal_pressure_pa, contact_modulus, slope_rms) -> np.ndarray:
    """p0 d(A_real/A0)/dp0 = (2 / sqrt(pi)) x exp(-x^2), x = sqrt(2) p0 / (E* h'_rms): how strongly
    the contact share answers a small relative change of the local pressure. It equals A_real/A0
    at light load (linear contact) and vanishes at full contact."""
    x = np.sqrt(2.0) * np.maximum(np.asarray(nominal_pressure_pa, dtype=np.float64), 0.0) \
        / (contact_modulus * slope_rms)
    return (2.0 / np.sqrt(np.pi)) * x * np.exp(-x * x)


def surface_profile(rng, length_mm, step_mm, hurst_exponent, roll_off_mm, cutoff_mm) -> np.ndarray:
    """A unit-rms line scan of the self-affine surface, sampled every `step_mm` over `length_mm`
    (wavelengths shorter than 2 steps or than the cutoff are absent)."""
    check_roughness(1.0, hurst_exponent, roll_off_mm, cutoff_mm)
    n = int(np.ceil(length_mm / step_mm))
    n_fft = 1 << int(np.ceil(np.log2(max(n, 2))))
    amplitude = _line_scan_amplitude(n_fft, float(step_mm), float(hurst_exponent), float(roll_off_mm),
                                     float(cutoff_mm))
    phases = rng.uniform(0, 2 * np.pi, size=amplitude.size)
    profile = np.fft.irfft(amplitude * np.exp(1j * phases), n=n_fft)[:n]
    std = profile.std()
    return profile / std if std > 0 else profile
