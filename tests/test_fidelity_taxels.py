"""The taxels fidelity rows (runs/fidelity/taxels.py, docs/taxels.md): every observation of the
taxels paper has a row, the rows that hold keep holding on fewer noise seeds than the table, and
the one that does not (shear sensitivity) fails for its measured reason."""
import pytest

from runs.fidelity import taxels as rows
from runs.fidelity.observations import CHECKS, scene_params
from runs.studies.taxel_receptive_field import THEORY


@pytest.fixture(scope="module")
def probe():
    return rows.TaxelsProbe(scene_params("taxels"), repeats=3)


def test_every_observation_of_the_taxels_paper_has_a_row():
    assert [fn.observation[1] for fn in CHECKS["taxels"]] == ["1", "2", "3", "4", "5", "6"]


def test_lateral_inhibition_is_within_30_percent_of_the_measured_19(probe):
    measured = rows.lateral_inhibition(probe)
    assert measured.holds
    assert 19 * 0.7 < measured.numbers["mechanics"] < 19 * 1.3          # table: 21.8
    mean, sd = measured.numbers["read_back"]
    assert 19 * 0.7 < mean < 19 * 1.3 and sd > 0                           # table: 15.4 ± 0.9 (20 seeds)


def test_width_slope_lies_between_the_measurement_and_the_theory(probe):
    measured = rows.width_slope(probe)
    assert measured.holds and 1.14 < measured.numbers["w_slope"] < 2.83   # table: 2.69


def test_amplitude_law_is_near_the_measured_exponent(probe):
    measured = rows.amplitude_exponent(probe)
    assert measured.holds and abs(measured.numbers["a_exponent"] + 1.45) < 0.25   # table: -1.25


def test_shear_sensitivity_row_fails_for_its_measured_reason(probe):
    """The membrane average raises max|gamma_x|/max|eps_z| above eq. (1)'s 0.429 (the paper's
    sensor is below it); the hair still raises it, as measured."""
    measured = rows.shear_below_theory(probe)
    assert not measured.holds
    assert measured.numbers["mechanics"] > THEORY["shear_sensitivity"]   # table: 0.534
    assert measured.numbers["hair"] > 2 * measured.numbers["flat"]       # table: 4.50 vs 0.51


def test_bumps_raise_the_lateral_sensitivity(probe):
    measured = rows.bump_raises_lateral_sensitivity(probe)
    assert measured.holds and measured.numbers["gain"][0] > 2.0          # table: 3.23 ± 0.05


def test_ridges_are_direction_selective(probe):
    measured = rows.ridge_direction_selective(probe)
    assert measured.holds                                                # table: 1.49, correlation 0.999
    assert measured.numbers["selectivity"] > 1.2 and measured.numbers["shape_correlation"] > 0.95
