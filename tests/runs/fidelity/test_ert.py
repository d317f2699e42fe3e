"""Seed 002's fidelity rows (runs/fidelity/ert.py): the rows that hold, asserted on the scene."""
import pytest

from runs.fidelity import ert
from runs.fidelity.observations import CHECKS, CONFIGS, scene_params


def probe(*overrides):
    return ert.ErtProbe(scene_params(CONFIGS["ert"], overrides))


@pytest.fixture(scope="module")
def small_grid():
    """The paper's single-point protocol on a 9 x 9 grid (seeds 0-2, both layouts), run once for
    the slow rows."""
    return probe("scene.grid_points_per_side=9")


def test_every_row_of_seed_002_is_registered():
    numbers = [fn.observation[1] for fn in CHECKS["ert"]]
    assert numbers == ["1", "2", "3", "4", "5", "6", "7"]


def test_row5_optimal_injection_recruits_94_pairs_within_ten_iterations():
    measured = ert.optimal_injection(probe())
    assert measured.holds, measured.value
    counts = measured.numbers["counts"]
    assert counts[7] >= 94 and 1.0 - measured.numbers["errors"][7] > 0.6


def test_row6_transducer_law_holds():
    measured = ert.transducer_curve(probe())
    assert measured.holds, measured.value
    r = measured.numbers["r"]
    assert r[0] == 1.0 and r[1] == pytest.approx(1 - 0.696, abs=1e-6) and r[3] < 0.12


def test_row7_hysteresis_holds():
    measured = ert.hysteresis(probe())
    assert measured.holds, measured.value
    assert min(measured.numbers["per_frequency"]) > 0.03


@pytest.mark.slow
def test_row1_minimum_quantifiable_pressure_does_not_differ_between_layouts(small_grid):
    measured = ert.minimum_quantifiable_pressure(small_grid)
    assert measured.holds, measured.value


@pytest.mark.slow
def test_row4_internal_electrodes_estimate_force_better_at_every_seed(small_grid):
    measured = ert.force_estimation(small_grid)
    assert measured.holds, measured.value
    assert all(measured.numbers["at_seed"])
    assert measured.numbers["r"][0][0] > 0.95                     # the goal on internal electrodes
