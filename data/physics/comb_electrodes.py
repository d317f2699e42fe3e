"""What a pair of interdigitated comb electrodes reads from a charge pattern sliding under it.

The fingertip's six interleaved copper fingers (seed 003, sec. 2.2) form two combs of period
Lambda (one finger of each per period, each half a period wide). A surface-charge pattern rho(x)
on the board, seen through the thin Kapton skin, induces on the two combs charges that differ by

    dQ(X) = (1 / L) Int_0^L w(x) rho(X + x) dx,     w(x) = sign(sin(2 pi x / Lambda)),

the pattern weighted +1 over one comb's fingers and -1 over the other's, over the pad's length L
(the freestanding-mode grating of Niu & Wang, Nano Energy 14 (2015) 161; Zhu et al., Nat. Commun.
5 (2014) 3426 for the grating's period selectivity). In wave numbers, |W(q)| peaks at q = 2 pi / Lambda
(at 2/pi) and its odd harmonics, each about 2 pi / L wide: a uniform pattern gives nothing, and a
random one is read through a narrow band around the grating's wavelength. Sliding at speed v, that
band sits at v / Lambda in time.
"""
import numpy as np
from scipy.signal import fftconvolve

from common.errors import InputError


def comb_weights(step_mm: float, period_mm: float, length_mm: float) -> np.ndarray:
    if min(step_mm, period_mm, length_mm) <= 0:
        raise InputError(f"comb electrodes: step, period and length must be positive, got {step_mm}, "
                         f"{period_mm}, {length_mm} mm")
    x = (np.arange(round(length_mm / step_mm)) + 0.5) * step_mm
    return np.sign(np.sin(2 * np.pi * x / period_mm))


def comb_differential(pattern: np.ndarray, step_mm: float, period_mm: float, length_mm: float) -> np.ndarray:
    """dQ(X) / (charge scale) for a pattern sampled every `step_mm` (last axis), at each X where the
    whole pad lies on the pattern; the output is shorter by the pad's length in samples, minus one."""
    weights = comb_weights(step_mm, period_mm, length_mm)
    pattern = np.asarray(pattern, dtype=np.float64)
    if pattern.shape[-1] < weights.size:
        raise InputError(f"comb electrodes: a pattern of {pattern.shape[-1]} samples is shorter than the pad "
                         f"({weights.size} samples)")
    return fftconvolve(pattern, weights[::-1][None, :] if pattern.ndim == 2 else weights[::-1],
                       mode="valid", axes=-1) / weights.size
