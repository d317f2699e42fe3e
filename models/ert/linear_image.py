"""The estimator shared by the linear ERT reconstructions (gauss_newton.py, greit.py).

frame v (changes from the unloaded frame) -> u = K^T v (data/ert/readings.py) -> image = A u on a pixel
grid -> thresholded weighted centroid (image_readout.py) -> (x_mm, y_mm); force_n =
c0 + c1 m + c2 m^2 with m the thresholded image's mass. Only A and how it is built differ
between reconstructions: a subclass yields candidate maps (one per hyper-parameter setting),
and `fit` picks the candidate and the read-out threshold with the lowest mean localisation
error on the presses it is given, which are validation presses (a calibration recording),
never test presses. The force polynomial is then fitted on the same presses.
"""
import numpy as np
from sklearn.utils.validation import check_is_fitted

from common.errors import InputError
from data.ert.readings import transfer_basis
from models.ert.image_readout import thresholded_centroid
from models.ert.reconstruction import ERTReconstruction, localisation_mm
from models.ert.validation import checked_presses, checked_voltages, required_geometry


class LinearImageReconstruction(ERTReconstruction):
    """Subclasses set `geometry`, `thresholds`, `quantification_limit_n` and implement
    `_candidates(basis)` -> iterable of (params dict, A (n_pixels, n_z)) and `_centres()`."""

    def fit(self, X, y):
        """X: (n_presses, n_channels) validation voltages; y: (n_presses, 3) x_mm, y_mm, force_n."""
        required_geometry(self.geometry)
        thresholds = np.atleast_1d(np.asarray(self.thresholds, dtype=float))
        if thresholds.size == 0 or not ((thresholds >= 0) & (thresholds < 1)).all():
            raise InputError(f"model.thresholds must lie in [0, 1), got {thresholds.tolist()}")
        basis = transfer_basis(self.geometry)
        X, y = checked_presses(X, y, basis.shape[0], self.quantification_limit_n)
        u = np.asarray(basis.T @ X.T).T
        centres = self._centres()
        best, scores = None, []
        for params, image_map in self._candidates(basis):
            images = u @ image_map.T
            for threshold in thresholds:
                xy, _ = thresholded_centroid(images, centres, threshold)
                error = localisation_mm(xy, y)
                scores.append({**params, "threshold": float(threshold), "localisation_mm": error})
                if best is None or error < best[0]:
                    best = (error, params, float(threshold), image_map)
        _, self.params_, self.threshold_, self.image_map_ = best
        self.validation_scores_ = scores
        self.compression_ = np.asarray(basis.T.todense())          # (n_z, n_channels)
        self.pixel_centres_mm_ = centres
        _, mass = thresholded_centroid(u @ self.image_map_.T, centres, self.threshold_)
        design = np.column_stack([np.ones_like(mass), mass, mass ** 2])
        self.force_coefficients_ = np.linalg.lstsq(design, y[:, 2], rcond=None)[0]
        self.n_features_in_ = basis.shape[0]
        return self

    def chosen_hyperparameters(self) -> dict:
        return {**self.params_, "threshold": self.threshold_}

    def image(self, X) -> np.ndarray:
        """(n_frames, n_pixels) reconstructed image (rows in y, columns in x of `pixel_centres_mm_`)."""
        check_is_fitted(self, "image_map_")
        X = checked_voltages(X, self.n_features_in_)
        return (X @ self.compression_.T) @ self.image_map_.T

    def predict(self, X) -> np.ndarray:
        """(n_frames, 3): x_mm, y_mm (thresholded centroid) and force_n."""
        xy, mass = thresholded_centroid(self.image(X), self.pixel_centres_mm_, self.threshold_)
        c = self.force_coefficients_
        return np.column_stack([xy, c[0] + c[1] * mass + c[2] * mass ** 2])
