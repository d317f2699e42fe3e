"""The fingertip fidelity rows that hold (runs/fidelity/fingertip.py, docs/fidelity.md) keep
holding, with margin at every scene seed the table measures (0-2), on fewer passes than the table;
and Algorithm 1's diagnostic is measured over those seeds."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from runs.fidelity import fingertip as rows
from runs.fidelity.observations import CHECKS, scene_params

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def probe():
    return rows.FingertipProbe(scene_params("fingertip"), repeats=6)


def test_every_observation_of_seed_003_has_a_row():
    assert [fn.observation[1] for fn in CHECKS["fingertip"]] == ["1", "2", "3", "4", "5", "6"]


def test_boards_are_the_papers(probe):
    measured = rows.boards_match_the_paper(probe)
    assert measured.holds and all(measured.numbers["same"].values())


def test_triboelectric_separates_materials_at_one_level_not_across_levels(probe):
    measured = rows.triboelectric_separates_at_one_level(probe)    # at scene seeds 0-2, as the table
    assert measured.holds, measured.value
    one_level, pooled = (np.array(measured.numbers["by_seed"][k]) for k in ("one_level", "pooled"))
    assert (one_level > 0.5).all()                          # table: 80 ± 2 %, tolerance 2 x chance = 20 %
    assert (one_level > 2.0 * pooled).all()                 # table: 80 % vs 33 %, tolerance 1.3 x


def test_force_and_texture_show_in_both_channels(probe):
    measured = rows.force_and_texture_in_both_channels(probe)
    assert measured.holds, measured.value
    assert (np.array(measured.numbers["by_seed"]["force_error"]) < 0.02).all()   # table: 0.3 %, tolerance 5 %
    assert min(measured.numbers["by_seed"]["fewest_hits"]) >= 11                 # table: 11.7 ± 0.6 of 12, tolerance 10


def test_training_rows_say_where_they_are_measured(probe):
    for fn in CHECKS["fingertip"][3:]:
        measured = fn(probe)
        assert measured.holds is None and "training runs" in measured.value


def test_algorithm1_diagnostic_covers_every_class_and_unseen_level(probe):
    diagnostic = rows.algorithm1_diagnostic(probe)
    assert len(diagnostic["error"]) == 10
    for errors in diagnostic["error"].values():
        assert set(errors) == {5.0, 20.0} and all(np.isfinite(list(errors.values())))
    assert set(diagnostic["pass_cv"]) == {1.0, 5.0, 10.0, 15.0, 20.0, 25.0}
    assert diagnostic["seeds"] == (0, 1, 2) and diagnostic["sd"]["error"].keys() == diagnostic["error"].keys()
    assert all(np.isfinite(list(errors.values())).all() for errors in diagnostic["sd"]["error"].values())
    text = rows.diagnostic_markdown(diagnostic)
    assert text.count("\n") == 2 + 10 + 1 + 2 + 6 - 1      # two tables, a blank line between


def test_fidelity_script_prints_the_fingertip_table():
    out = subprocess.run([sys.executable, str(ROOT / "bench" / "fidelity.py"), "--scene", "fingertip", "--repeats", "2"],
                         capture_output=True, text=True, check=True).stdout
    assert "3 of 6 rows the paper supports hold (3 measured" in out and "Algorithm 1's cubic" in out
