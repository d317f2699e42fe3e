"""A learned inverse on top of GREIT (greit.py): a regressor learns, from simulated presses on
other sensors, the correction from GREIT's centroid to the press.

Inputs per frame: GREIT's centroid (x, y), the thresholded image's mass and the
(2h + 1)^2 image pixels around the image's arg-max pixel (zero outside the grid); targets: the
press minus the centroid, and the force. The window moves with the press, so what the regressor
learns (how the image's shape encodes where inside a fabric patch the press sits) carries over
between places. Training presses are GREIT's own training set: `n_training_sensors` simulated
sensors (seeds `training_seed` + k, never the sensor under test), so the regressor is judged on
an instance it never saw, with that instance's manufacturing spread. `fit(X, y)` receives the
validation presses (a calibration recording of the sensor under test): GREIT chooses its
hyper-parameters there; the regressor never sees them.
"""
import numpy as np
from sklearn.utils.validation import check_is_fitted

from common.errors import InputError
from models.ert.greit import GreitReconstruction
from models.ert.image_readout import thresholded_centroid, window_around_peak
from models.ert.reconstruction import ERTReconstruction
from models.trees import TreeRegressor

REGRESSOR_PARAMS = ("half_width_px", "n_estimators", "max_features")


class GreitLearnedInverse(ERTReconstruction):
    """ERT voltages -> (x_mm, y_mm, force_n): GREIT, then a regressor trained on other sensors."""

    @classmethod
    def for_sensor(cls, geometry, training_scene, seed, **params) -> "GreitLearnedInverse":
        """GREIT's settings and the regressor's (REGRESSOR_PARAMS) in one mapping, as a study gives them."""
        own = {k: params.pop(k) for k in REGRESSOR_PARAMS if k in params}
        return cls(greit=GreitReconstruction.for_sensor(geometry, training_scene, seed, **params), seed=seed, **own)

    def training_sensor_seeds(self) -> list[int]:
        return (self.greit if self.greit is not None else GreitReconstruction()).training_sensor_seeds()

    def chosen_hyperparameters(self) -> dict:
        return self.greit_.chosen_hyperparameters()

    def validation_localisation_mm(self) -> float:
        return self.greit_.validation_localisation_mm()

    def __init__(self, greit=None, half_width_px=3, n_estimators=300, max_features=0.5, seed=0):
        self.greit = greit
        self.half_width_px = half_width_px
        self.n_estimators = n_estimators
        self.max_features = max_features
        self.seed = seed

    def _features(self, images) -> tuple[np.ndarray, np.ndarray]:
        """(centroid (n, 2), features (n, 3 + (2h + 1)^2))."""
        g = self.greit_
        xy, mass = thresholded_centroid(images, g.pixel_centres_mm_, g.threshold_)
        _, _, window = window_around_peak(images, g.pixels_per_side, self.half_width_px)
        scale = np.maximum(images.max(axis=1, keepdims=True), 1e-300)
        return xy, np.column_stack([xy, mass, window / scale])

    def fit(self, X, y):
        """X, y: validation presses of the sensor under test (GREIT's hyper-parameters only)."""
        if int(self.half_width_px) < 0:
            raise InputError(f"model.half_width_px must be >= 0, got {self.half_width_px}")
        base = self.greit if self.greit is not None else GreitReconstruction()
        if not isinstance(base, GreitReconstruction):
            raise InputError("model.greit must be a GreitReconstruction")
        self.greit_ = GreitReconstruction(**base.get_params()).fit(X, y)
        voltages, targets = self.greit_.training_frames()
        centroid, features = self._features(self.greit_.image(voltages))
        residual = np.column_stack([targets[:, :2] - centroid, targets[:, 2]])
        self.regressor_ = TreeRegressor(kind="extra_trees", n_estimators=self.n_estimators, max_depth=None,
                                        max_features=self.max_features, n_jobs=1, seed=self.seed).fit(features, residual)
        self.n_features_in_ = self.greit_.n_features_in_
        return self

    def predict(self, X) -> np.ndarray:
        check_is_fitted(self, "regressor_")
        centroid, features = self._features(self.greit_.image(X))
        residual = self.regressor_.predict(features)
        return np.column_stack([centroid + residual[:, :2], residual[:, 2]])
