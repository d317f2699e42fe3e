"""ERT single-point localisation tested off the calibration grid (issue 42).

The paper's test (runs/studies/ert_tests.py, `experiment=ert_localisation`) presses the same 18 x 18
grid of points the calibration recording visits, so a reconstruction whose hyper-parameters (or
weights) are chosen on that recording is tested where it was tuned. Here the calibration recording
is the same as today, and the test presses are drawn at random: positions uniform over the square
the grid's points span, at a given force, on the sensor under test (seed). Each press is simulated
by the scene's own `simulate`, so every listed effect (drift, noise, re-taken unloaded frames)
applies as in the paper's test. The error is the distance from the reconstruction's peak to the
press; the distance from each press to its nearest calibration point is reported beside it (how far
off the grid the presses are).

Which inputs each reconstruction uses: the calibration recording of the sensor under test (its
presses at known grid positions and forces) and each test frame's change from the recording's
unloaded frame; GREIT and the learned inverses also train on simulated presses of other sensors
(models/ert/registry.py). None uses the test presses' positions.
"""
import numpy as np
import pandas as pd

from data.scenes.contract import random_generator_for
from runs.studies.ert_tests import calibrate, scene_for


def off_grid_presses(scene, n: int, force_n: float, seed: int) -> np.ndarray:
    """(n, 1, 3) presses [x_mm, y_mm, force_n] at uniform random positions over the square the
    calibration grid's points span; their own random stream, apart from the scene's."""
    points = scene.grid_points_mm()
    low, high = points.min(), points.max()
    xy = random_generator_for(seed, "off_grid_presses").uniform(low, high, size=(n, 2))
    return np.column_stack([xy, np.full(n, float(force_n))])[:, None, :]


def nearest_grid_distance_mm(xy: np.ndarray, grid: np.ndarray) -> np.ndarray:
    return np.sqrt(((xy[:, None, :] - grid[None, :, :]) ** 2).sum(axis=2)).min(axis=1)


def _scored(test, model, seed: int, grid: np.ndarray, placement: str) -> pd.DataFrame:
    prediction = model.predict(test.channels)
    frame = pd.DataFrame(test.targets, columns=["x_mm", "y_mm", "force_n"])
    frame[["x_pred_mm", "y_pred_mm", "force_pred_n"]] = prediction
    frame["seed"], frame["placement"] = seed, placement
    frame["error_mm"] = np.hypot(frame.x_pred_mm - frame.x_mm, frame.y_pred_mm - frame.y_mm)
    frame["grid_distance_mm"] = nearest_grid_distance_mm(frame[["x_mm", "y_mm"]].to_numpy(), grid)
    return frame


def off_grid_study(cfg, seeds=(0, 1, 2), calibration=None, reconstruction=None, forces_n=(10.0,),
                   n_presses=324) -> pd.DataFrame:
    """Per seed: calibrate as the paper's test does, then at each force press the paper's 324 grid
    points ("on_grid") and `n_presses` random points ("off_grid"), and predict with the one
    calibrated reconstruction. A frame of presses, predictions, errors and distances to the grid."""
    rows = []
    for seed in seeds:
        scene, model = calibrate(cfg, seed, dict(calibration or {}), dict(reconstruction or {}))
        grid = scene.grid_points_mm()
        tester = scene_for(cfg, seed=seed, protocol="single_point")
        for force in forces_n:
            on_grid = np.column_stack([grid, np.full(len(grid), float(force))])[:, None, :]
            rows.append(_scored(tester.simulate(on_grid), model, seed, grid, "on_grid"))
            off_grid = off_grid_presses(scene, n_presses, force, seed)
            rows.append(_scored(tester.simulate(off_grid), model, seed, grid, "off_grid"))
    return pd.concat(rows, ignore_index=True)
