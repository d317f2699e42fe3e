"""ERT localisation off the calibration grid: the test presses are not calibration points, are
seeded, and the one calibrated reconstruction localises both sets."""
import numpy as np
import pytest

from runs.studies.ert_off_grid import nearest_grid_distance_mm, off_grid_presses, off_grid_study
from runs.studies.ert_tests import scene_for

TINY = ["study.calibration.grid_points_per_side=4", "scene.grid_points_per_side=4", "scene.grid_nodes=21",
        "study.reconstruction.pixels_per_side=8", "scene.injection=adjacent"]


@pytest.fixture
def cfg(compose_config):
    return compose_config(["experiment=ert_localisation", "scene=ert_boundary", *TINY])


def test_off_grid_presses_are_not_calibration_points_and_are_seeded(cfg):
    scene = scene_for(cfg, seed=0, protocol="calibration", grid_points_per_side=4)
    grid = scene.grid_points_mm()
    presses = off_grid_presses(scene, 200, 10.0, seed=0)
    xy = presses[:, 0, :2]
    assert (nearest_grid_distance_mm(xy, grid) > 1e-6).all()
    assert xy.min() >= grid.min() and xy.max() <= grid.max()          # within the span the grid covers
    np.testing.assert_array_equal(presses, off_grid_presses(scene, 200, 10.0, seed=0))
    assert not np.allclose(presses, off_grid_presses(scene, 200, 10.0, seed=1))
    assert (presses[:, 0, 2] == 10.0).all()


def test_nearest_grid_distance_is_zero_on_the_grid_and_exact_between():
    grid = np.array([[0.0, 0.0], [10.0, 0.0]])
    np.testing.assert_allclose(nearest_grid_distance_mm(np.array([[0.0, 0.0], [4.0, 3.0], [10.0, 2.0]]), grid),
                               [0.0, 5.0, 2.0])


def test_one_calibration_localises_on_and_off_the_grid(cfg):
    study = cfg.study
    frame = off_grid_study(cfg, seeds=(0,), calibration=dict(study.calibration),
                           reconstruction=dict(study.reconstruction), forces_n=(10.0,), n_presses=20)
    assert set(frame.placement) == {"on_grid", "off_grid"}
    on, off = frame[frame.placement == "on_grid"], frame[frame.placement == "off_grid"]
    assert len(on) == 16 and len(off) == 20
    assert (on.grid_distance_mm == 0).all() and (off.grid_distance_mm > 0).all()
    assert np.isfinite(frame.error_mm).all() and (frame.error_mm < 200).all()
