"""Regularisation priors R of a one-step Gauss-Newton reconstruction (J^T J + lambda R)^-1 J^T
(Adler, Dai & Lionheart, Physiol. Meas. 28, 2007; Holder 2005 ch. 2):
- `tikhonov`: R = I (damped least squares: small images);
- `laplacian`: R = L^T L, L the pixel grid's 5-point Laplacian (smooth images);
- `noser`: R = diag(J^T J) (Cheney et al., Int. J. Imaging Syst. Technol. 2, 1990: each pixel
  damped by its own sensitivity, so weakly seen pixels far from the electrodes are not
  amplified).
"""
import numpy as np
import scipy.sparse as sp

from common.errors import InputError

PRIORS = ("tikhonov", "laplacian", "noser")


def pixel_laplacian(n: int) -> np.ndarray:
    """5-point Laplacian on an n x n pixel grid with no-flux edges (rows sum to zero)."""
    second = sp.diags([1.0, -2.0, 1.0], [-1, 0, 1], shape=(n, n)).tolil()
    second[0, 0] = second[-1, -1] = -1.0
    second = second.tocsr()
    eye = sp.identity(n)
    return (sp.kron(eye, second) + sp.kron(second, eye)).toarray()


def prior_matrix(name: str, jtj: np.ndarray, pixels_per_side: int) -> np.ndarray:
    """R for prior `name`, scaled so trace(R) = trace(J^T J): lambda is then relative."""
    if name == "tikhonov":
        r = np.eye(len(jtj))
    elif name == "laplacian":
        laplacian = pixel_laplacian(pixels_per_side)
        r = laplacian.T @ laplacian
    elif name == "noser":
        r = np.diag(np.diag(jtj))
    else:
        raise InputError(f"unknown prior '{name}'; expected one of {', '.join(PRIORS)}")
    return r * (np.trace(jtj) / max(np.trace(r), 1e-300))
