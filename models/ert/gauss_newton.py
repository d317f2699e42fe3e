"""One-step Gauss-Newton (linearised difference) reconstruction of an ERT skin with a choice of
prior: image = (J^T J + lambda R)^-1 J^T v (Holder 2005 ch. 2; Adler et al. 2007), J the
channels' Jacobian with respect to each pixel's relative conductance at the nominal, uniform
sheet (adjoint sensitivity, data/ert/jacobian.py), R from priors.py. The prior, lambda (relative to
trace(J^T J)) and the read-out threshold are chosen on the validation presses given to `fit`
(linear_image.py). Through u = K^T v: image = (J^T J + lambda R)^-1 J_z^T u, J = K J_z.
"""
import numpy as np

from common.errors import InputError
from data.ert.jacobian import pixel_sensitivity
from models.ert.linear_image import LinearImageReconstruction
from models.ert.pixel_grid import pixel_centres_mm
from models.ert.priors import PRIORS, prior_matrix


class GaussNewtonReconstruction(LinearImageReconstruction):
    """ERT voltages (changes from the unloaded frame) -> (x_mm, y_mm, force_n)."""

    def __init__(self, geometry=None, pixels_per_side=20, priors=PRIORS,
                 lambdas_relative=(1e-4, 1e-3, 1e-2, 1e-1), thresholds=(0.3, 0.5, 0.7),
                 quantification_limit_n=2.0):
        self.geometry = geometry
        self.pixels_per_side = pixels_per_side
        self.priors = priors
        self.lambdas_relative = lambdas_relative
        self.thresholds = thresholds
        self.quantification_limit_n = quantification_limit_n

    def _centres(self):
        return pixel_centres_mm(self.geometry["side_mm"], self.pixels_per_side)

    def _candidates(self, basis):
        lambdas = np.atleast_1d(np.asarray(self.lambdas_relative, dtype=float))
        if lambdas.size == 0 or not (np.isfinite(lambdas) & (lambdas > 0)).all():
            raise InputError(f"model.lambdas_relative must be positive, got {lambdas.tolist()}")
        if int(self.pixels_per_side) < 2:
            raise InputError(f"model.pixels_per_side must be >= 2, got {self.pixels_per_side}")
        priors = [self.priors] if isinstance(self.priors, str) else list(self.priors)
        unknown = [p for p in priors if p not in PRIORS]
        if not priors or unknown:
            raise InputError(f"model.priors must name some of {', '.join(PRIORS)}, got {priors}")
        jz = pixel_sensitivity(self.geometry, int(self.pixels_per_side))       # (n_z, n_pixels)
        kk = np.asarray((basis.T @ basis).todense())
        jtj = jz.T @ kk @ jz
        for prior in priors:
            r = prior_matrix(prior, jtj, int(self.pixels_per_side))
            for lam in lambdas:
                yield {"prior": prior, "lambda_relative": float(lam)}, np.linalg.solve(jtj + lam * r, jz.T)
