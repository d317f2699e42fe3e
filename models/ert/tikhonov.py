"""Tikhonov reconstruction and calibration of an ERT skin (seed 002 §2 eq. 3-4 and §4.3, fig. 10).

Three mapping stages, all linear up to the last step, so a frame costs one matrix product:
1. voltages -> conductance image: dsigma = Q dE with Q = (J^T J + alpha^2 Gamma^T Gamma)^-1 J^T
   (eq. 4), J the Jacobian of the readings with respect to each pixel's relative conductance at
   the unloaded sheet (adjoint sensitivity, data/ert/jacobian.py), Gamma the identity
   or the pixel grid's Laplacian;
2. a Gaussian deconvolution: the blur of a point press is modelled as a Gaussian point-spread
   function of sd `deconvolution_sigma_mm` (seed 002 assumes identical Gaussian kernels), and
   undone with a Wiener filter (Gonzalez & Woods, *Digital Image Processing*, §5.8) truncated to
   a small convolution kernel;
3. a coefficient field W turns the image into per-pixel force: force = sum_p W_p D_p over the
   calibration presses, fitted by least squares with a smoothness penalty on W (the paper's
   supplement is not given; this is our reading of "a coefficient field from single-point
   indentations").
The pressure field is W * D per pixel area, upsampled bilinearly to `field_pixels` squared (the
paper's 100 x 100); the position is the field's peak and the force its sum.

alpha is chosen on a validation split of the calibration presses (mean localisation error,
ties broken by force error): neither GCV nor the L-curve sees the calibration, which is what
the reconstruction is judged on. The grid `alpha_relative` is relative: alpha^2 = a x
mean diag(J^T J) / mean diag(Gamma^T Gamma).
"""
import numpy as np
from scipy.ndimage import correlate
from sklearn.utils.validation import check_is_fitted

from common.errors import InputError
from data.ert.jacobian import pixel_sensitivity
from data.ert.readings import transfer_basis
from models.ert.image_readout import window_around_peak
from models.ert.priors import pixel_laplacian
from models.ert.reconstruction import ERTReconstruction, localisation_mm
from models.ert.validation import checked_presses, checked_voltages, required_geometry


def bilinear_matrix(n_out: int, n_in: int) -> np.ndarray:
    """(n_out, n_in) linear interpolation between pixel centres (edge pixels held flat)."""
    centres_out = (np.arange(n_out) + 0.5) * n_in / n_out - 0.5
    position = np.clip(centres_out, 0.0, n_in - 1.0)
    low = np.floor(position).astype(int)
    high = np.minimum(low + 1, n_in - 1)
    frac = position - low
    matrix = np.zeros((n_out, n_in))
    matrix[np.arange(n_out), low] += 1.0 - frac
    matrix[np.arange(n_out), high] += frac
    return matrix


def wiener_kernel(sigma_px: float, noise_to_signal: float, half_width: int, n: int) -> np.ndarray:
    """A (2k+1)^2 spatial kernel undoing a Gaussian blur of sd sigma_px pixels: the Wiener filter
    H* / (|H|^2 + nsr) on a 4n grid, brought back to space and truncated."""
    size = 4 * n
    f = np.fft.fftfreq(size)
    fx, fy = np.meshgrid(f, f, indexing="ij")
    transfer = np.exp(-2.0 * (np.pi * sigma_px) ** 2 * (fx ** 2 + fy ** 2))
    inverse = np.real(np.fft.ifft2(transfer / (transfer ** 2 + noise_to_signal)))
    kernel = np.fft.fftshift(inverse)
    centre = size // 2
    kernel = kernel[centre - half_width: centre + half_width + 1, centre - half_width: centre + half_width + 1]
    return kernel / kernel.sum()      # keeps a flat image's level (and so the force scale)


class TikhonovReconstruction(ERTReconstruction):
    """ERT voltages (changes from the unloaded frame) -> (x_mm, y_mm, force_n).

    `geometry` is the scene's nominal geometry (data.scenes.ert.ERTScene.geometry()): the
    reconstruction knows the drawn sensor, not the one the sensor effects made of it.
    """

    offers_pressure_field = True

    def __init__(self, geometry=None, pixels_per_side=20, regulariser="laplacian",
                 alpha_relative=(1e-4, 1e-3, 1e-2, 1e-1, 1.0), deconvolution_sigma_mm=10.0,
                 deconvolution_noise=0.05, deconvolution_half_width=3, weight_smoothing=1.0,
                 quantification_limit_n=2.0, validation_fraction=0.25, field_pixels=100, seed=0):
        self.geometry = geometry
        self.pixels_per_side = pixels_per_side
        self.regulariser = regulariser
        self.alpha_relative = alpha_relative
        self.deconvolution_sigma_mm = deconvolution_sigma_mm
        self.deconvolution_noise = deconvolution_noise
        self.deconvolution_half_width = deconvolution_half_width
        self.weight_smoothing = weight_smoothing
        self.quantification_limit_n = quantification_limit_n
        self.validation_fraction = validation_fraction
        self.field_pixels = field_pixels
        self.seed = seed

    # -- stage 0: the forward model ---------------------------------------------------------------
    def jacobian(self) -> np.ndarray:
        """(n_channels, n_pixels) d voltage / d (relative pixel conductance) at the unloaded sheet."""
        return np.asarray(transfer_basis(self.geometry) @ pixel_sensitivity(self.geometry, self.pixels_per_side))

    def _check_params(self):
        required_geometry(self.geometry)
        alphas = np.atleast_1d(np.asarray(self.alpha_relative, dtype=float))
        if alphas.size == 0 or not np.all(np.isfinite(alphas)) or (alphas <= 0).any():
            raise InputError(f"model.alpha_relative must be positive, got {np.asarray(self.alpha_relative).tolist()}")
        if self.regulariser not in ("identity", "laplacian"):
            raise InputError(f"model.regulariser must be identity or laplacian, got '{self.regulariser}'")
        if self.pixels_per_side < 2 or self.deconvolution_sigma_mm < 0:
            raise InputError(f"model.pixels_per_side must be >= 2 and deconvolution_sigma_mm >= 0, got "
                             f"{self.pixels_per_side} and {self.deconvolution_sigma_mm}")
        return alphas

    # -- fit ---------------------------------------------------------------------------------------
    def fit(self, X, y):
        """X: (n_presses, n_channels) calibration voltages; y: (n_presses, 3) x_mm, y_mm, force_n."""
        alphas = self._check_params()
        J = self.jacobian()
        X, y = checked_presses(X, y, J.shape[0], self.quantification_limit_n, role="calibration")
        n = self.pixels_per_side
        gamma = np.eye(n * n) if self.regulariser == "identity" else pixel_laplacian(n)
        jtj, gtg = J.T @ J, gamma.T @ gamma
        scale = np.trace(jtj) / max(np.trace(gtg), 1e-300)
        pixel_mm = self.geometry["side_mm"] / n
        self.kernel_ = (wiener_kernel(self.deconvolution_sigma_mm / pixel_mm, self.deconvolution_noise,
                                      self.deconvolution_half_width, n)
                        if self.deconvolution_sigma_mm > 0 else np.ones((1, 1)))
        self.upsample_ = bilinear_matrix(self.field_pixels, n)

        rng = np.random.default_rng(self.seed)
        order = rng.permutation(len(X))
        n_val = int(round(self.validation_fraction * len(X)))
        val, fit = order[:n_val], order[n_val:]
        if n_val == 0:
            val = fit
        scores = []
        for a in alphas:
            Q = np.linalg.solve(jtj + a * scale * gtg, J.T)
            images = self._deconvolve(X @ Q.T)
            W = self._coefficient_field(images[fit], y[fit, 2])
            xy, force = self._locate(images[val] * W)
            scores.append((localisation_mm(xy, y[val]), np.abs(force - y[val, 2]).mean()))
        best = min(range(len(alphas)), key=lambda k: scores[k])
        self.alpha_relative_ = float(alphas[best])
        self.validation_scores_ = np.array(scores)
        self.inverse_ = np.linalg.solve(jtj + alphas[best] * scale * gtg, J.T)    # (n_pixels, n_channels)
        self.coefficient_field_ = self._coefficient_field(self._deconvolve(X @ self.inverse_.T), y[:, 2])
        self.n_features_in_ = J.shape[0]
        return self

    def _deconvolve(self, images_flat):
        n = self.pixels_per_side
        images = images_flat.reshape(-1, n, n)
        return np.stack([correlate(im, self.kernel_, mode="constant") for im in images]).reshape(len(images), -1)

    def _coefficient_field(self, images, force):
        """W minimising ||images W - force||^2 + lambda ||L W||^2 (L the pixel Laplacian), with
        lambda = weight_smoothing x trace(A^T A) / trace(L^T L), plus a tiny ridge."""
        laplacian = pixel_laplacian(self.pixels_per_side)
        ata = images.T @ images
        lam = self.weight_smoothing * np.trace(ata) / np.trace(laplacian.T @ laplacian)
        ridge = 1e-9 * np.trace(ata) / len(ata) + 1e-300
        return np.linalg.solve(ata + lam * laplacian.T @ laplacian + ridge * np.eye(len(ata)), images.T @ force)

    def _locate(self, force_pixels):
        """Peak of the upsampled field (x, y in mm) and the total force."""
        n, m = self.pixels_per_side, self.field_pixels
        field = self.upsample_ @ force_pixels.reshape(-1, n, n) @ self.upsample_.T
        index = field.reshape(len(field), -1).argmax(axis=1)
        step = self.geometry["side_mm"] / m
        xy = np.column_stack([(index % m + 0.5) * step, (index // m + 0.5) * step])
        return xy, force_pixels.sum(axis=1)

    def chosen_hyperparameters(self) -> dict:
        return {"alpha_relative": self.alpha_relative_}

    def validation_localisation_mm(self) -> float:
        return float(self.validation_scores_.min(axis=0)[0])

    # -- predict -----------------------------------------------------------------------------------
    def force_pixels(self, X) -> np.ndarray:
        """(n_frames, n_pixels) force carried by each reconstruction pixel, in newtons."""
        check_is_fitted(self, "inverse_")
        X = checked_voltages(X, self.n_features_in_)
        return self._deconvolve(X @ self.inverse_.T) * self.coefficient_field_

    def peak_window(self, X, half_width_px: int = 2) -> tuple[np.ndarray, np.ndarray]:
        """Features for a learned correction of the reconstruction: (peak_xy_mm (n, 2), features
        (n, 3 + (2h + 1)^2)). The peak is the force-pixel image's largest pixel (its centre in mm);
        the features are that centre, the image's total force and the (2h + 1)^2 pixels around the
        peak (zero outside the sheet). The window moves with the press, so what a model learns
        from it (sub-pixel position from how the load shares between neighbouring pixels) carries
        over between places; a drift of the base fabric adds only its small local share."""
        pixels = self.force_pixels(X)
        n = self.pixels_per_side
        if int(half_width_px) < 0:
            raise InputError(f"peak_window: half_width_px must be >= 0, got {half_width_px}")
        iy, ix, window = window_around_peak(pixels, n, half_width_px)
        pixel_mm = self.geometry["side_mm"] / n
        peak_xy_mm = np.column_stack([(ix + 0.5) * pixel_mm, (iy + 0.5) * pixel_mm])
        return peak_xy_mm, np.column_stack([peak_xy_mm, pixels.sum(axis=1), window])

    def predict(self, X) -> np.ndarray:
        """(n_frames, 3): x_mm, y_mm of the pressure field's peak and force_n, its integral."""
        xy, force = self._locate(self.force_pixels(X))
        return np.column_stack([xy, force])

    def pressure_field_kpa(self, X) -> np.ndarray:
        """(n_frames, field_pixels, field_pixels) pressure in kPa, rows in y, columns in x."""
        n = self.pixels_per_side
        pixel_area_mm2 = (self.geometry["side_mm"] / n) ** 2
        pressure = self.force_pixels(X).reshape(-1, n, n) / pixel_area_mm2 * 1e3   # N/mm^2 = MPa -> kPa
        return self.upsample_ @ pressure @ self.upsample_.T
