"""What every ERT reconstruction shares: a scikit-learn regressor from a frame of voltages (changes
from the unloaded frame) to (x_mm, y_mm, force_n), fitted on presses of the sensor under test
(a calibration recording, never test presses), built for one simulated sensor by `for_sensor`,
and able to say what it chose on those presses. The studies (runs/studies/ert_tests.py) and the
benches handle every reconstruction through this contract and the registry (registry.py),
never by its class."""
import time

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted


class ERTReconstruction(RegressorMixin, BaseEstimator):
    """Subclasses store their keyword arguments in `__init__`, implement `fit(X, y)` (setting
    `validation_scores_`), `predict(X)` and `chosen_hyperparameters()`."""

    # a calibrated pressure field over the sheet (`pressure_field_kpa`), which ert_two_point reads
    offers_pressure_field = False

    @classmethod
    def for_sensor(cls, geometry: dict, training_scene: dict, seed: int, **params) -> "ERTReconstruction":
        """The reconstruction for sensor `seed` of a scene: the nominal geometry, the scene's
        parameters (to simulate training presses on other sensors) and the seed go to those of
        `geometry`, `training_scene` and `seed` that this class takes; `params` are its settings."""
        given = {"geometry": geometry, "training_scene": training_scene, "seed": seed}
        return cls(**{k: v for k, v in given.items() if k in cls._get_param_names()}, **params)

    def training_sensor_seeds(self) -> list[int]:
        """Seeds of the simulated sensors it trains on (none here: it learns from the sensor
        under test's own presses or from nothing)."""
        return []

    def chosen_hyperparameters(self) -> dict:
        """What `fit` chose on the presses it was given."""
        raise NotImplementedError

    def validation_localisation_mm(self) -> float:
        """The chosen setting's mean localisation error on the presses `fit` was given."""
        check_is_fitted(self, "validation_scores_")
        return min(row["localisation_mm"] for row in self.validation_scores_)

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.target_tags.required = True
        tags.target_tags.multi_output = True       # x_mm, y_mm, force_n
        tags.target_tags.single_output = False
        return tags


def localisation_mm(xy: np.ndarray, targets: np.ndarray) -> float:
    """Mean distance between positions (n, 2) and the targets' x_mm, y_mm."""
    return float(np.hypot(*(xy - targets[:, :2]).T).mean())


def per_frame_ms(predict, frames: np.ndarray, calls: int = 50) -> float:
    """Median milliseconds of `predict` on one frame at a time (batch 1), cycling through `frames`."""
    times = []
    for k in range(calls):
        frame = frames[k % len(frames)][None]
        start = time.perf_counter()
        predict(frame)
        times.append(time.perf_counter() - start)
    return 1e3 * float(np.median(times))
