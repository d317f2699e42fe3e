"""GREIT-style reconstruction (Adler et al., "GREIT: a unified approach to 2D linear EIT
reconstruction of lung images", Physiol. Meas. 30, 2009): a linear map R from readings to an
image, trained on simulated small targets so that each target's image is a desired image
(here a Gaussian blob of sd `desired_radius_mm` at the target, its height the press force),
with a noise term:

    R = argmin sum_k || x_k - R y_k ||^2 + lambda E||R n||^2
      = X Y^T (Y Y^T + lambda Sigma_n)^-1                    (Adler et al. 2009, eq. 8 and 10)

The figures of merit the desired image encodes: uniform amplitude response (height = force
everywhere), no position error (the blob sits on the target), uniform resolution (one blob
size), no shape deformation (round) and no ringing (positive everywhere). The targets are
the skin's own small targets: indenter presses simulated by the scene (`training_scene`, the
ERTScene parameters with its effects) on `n_training_sensors` simulated sensors whose seeds
(`training_seed` + k) are not the sensor under test, so manufacturing spread is in the
training set. The image grid may extend `margin_mm` beyond the sheet, so a blob near an edge is
not cut off and its centroid is not pulled inwards. Everything runs in u = K^T y
(data/ert/readings.py), with Sigma_n = K^T K (white channel noise). lambda (relative to
trace(Y Y^T) / trace(Sigma_n)), the desired radius and the read-out threshold are chosen on
the validation presses given to `fit` (linear_image.py).
"""
import json
from functools import lru_cache

import numpy as np

from common.errors import InputError
from data.scenes.ert import ERTScene
from models.ert.linear_image import LinearImageReconstruction
from models.ert.pixel_grid import pixel_centres_mm


class GreitReconstruction(LinearImageReconstruction):
    """ERT voltages (changes from the unloaded frame) -> (x_mm, y_mm, force_n)."""

    def __init__(self, geometry=None, training_scene=None, pixels_per_side=48, margin_mm=40.0,
                 desired_radius_mm=(10.0, 15.0, 20.0), noise_weights=(1e-3, 1e-2, 1e-1),
                 thresholds=(0.3, 0.5, 0.7), n_training_sensors=4, presses_per_sensor=1000,
                 training_force_range_n=(2.0, 15.0), training_position_range_mm=(0.0, 200.0),
                 training_seed=10_000, quantification_limit_n=2.0):
        self.geometry = geometry
        self.training_scene = training_scene
        self.pixels_per_side = pixels_per_side
        self.margin_mm = margin_mm
        self.desired_radius_mm = desired_radius_mm
        self.noise_weights = noise_weights
        self.thresholds = thresholds
        self.n_training_sensors = n_training_sensors
        self.presses_per_sensor = presses_per_sensor
        self.training_force_range_n = training_force_range_n
        self.training_position_range_mm = training_position_range_mm
        self.training_seed = training_seed
        self.quantification_limit_n = quantification_limit_n

    def _centres(self):
        return pixel_centres_mm(self.geometry["side_mm"], int(self.pixels_per_side), float(self.margin_mm))

    def training_sensor_seeds(self) -> list[int]:
        return [int(self.training_seed) + k for k in range(int(self.n_training_sensors))]

    def training_frames(self) -> tuple[np.ndarray, np.ndarray]:
        """(voltages, targets) of the simulated training presses."""
        if not isinstance(self.training_scene, dict):
            raise InputError("model.training_scene is required: the scene's parameters (a mapping) to simulate "
                             "training presses with")
        if int(self.n_training_sensors) < 1 or int(self.presses_per_sensor) < 1:
            raise InputError(f"model.n_training_sensors and presses_per_sensor must be >= 1, got "
                             f"{self.n_training_sensors} and {self.presses_per_sensor}")
        scenes = [{k: v for k, v in self.training_scene.items() if not k.startswith("_")}
                  | {"protocol": "random", "seed": seed, "n_samples": int(self.presses_per_sensor),
                     "force_range_n": list(self.training_force_range_n),
                     "position_range_mm": list(self.training_position_range_mm),
                     "two_contact_probability": 0.0, "recording_presses": None, "session": 0}
                  for seed in self.training_sensor_seeds()]
        voltages, targets = _simulated_presses(json.dumps(scenes, sort_keys=True))
        return voltages.copy(), targets.copy()

    def _candidates(self, basis):
        radii = np.atleast_1d(np.asarray(self.desired_radius_mm, dtype=float))
        weights = np.atleast_1d(np.asarray(self.noise_weights, dtype=float))
        if radii.size == 0 or not (radii > 0).all() or weights.size == 0 or not (weights > 0).all():
            raise InputError(f"model.desired_radius_mm and noise_weights must be positive, got {radii.tolist()} "
                             f"and {weights.tolist()}")
        voltages, targets = self.training_frames()
        u = np.asarray(basis.T @ voltages.T).T                           # (n_train, n_z)
        noise = np.asarray((basis.T @ basis).todense())
        signal = u.T @ u
        scale = np.trace(signal) / np.trace(noise)
        centres = self._centres()
        distance2 = ((targets[:, None, :2] - centres[None]) ** 2).sum(axis=-1)    # (n_train, n_pixels)
        for radius in radii:
            desired = targets[:, 2:3] * np.exp(-distance2 / (2.0 * radius ** 2))
            cross = desired.T @ u                                                 # (n_pixels, n_z)
            for weight in weights:
                image_map = np.linalg.solve(signal + weight * scale * noise, cross.T).T
                yield {"desired_radius_mm": float(radius), "noise_weight": float(weight)}, image_map


@lru_cache(maxsize=4)
def _simulated_presses(scenes_json: str) -> tuple[np.ndarray, np.ndarray]:
    """(voltages, targets) of the listed scenes' presses, stacked; kept per process, since every
    sensor under test reuses the same training presses (same seeds, same scene)."""
    tables = [ERTScene(**scene).generate() for scene in json.loads(scenes_json)]
    return np.vstack([t.channels for t in tables]), np.vstack([t.targets for t in tables])
