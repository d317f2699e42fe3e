"""models/paired_accuracy.py: McNemar's z, the reachable z and the paired difference's interval."""
import numpy as np
import pytest

from models.paired_accuracy import accuracy_difference, best_reachable_z, discordant, mcnemar_z, significantly_better


def test_only_discordant_rows_count_and_the_interval_covers_the_difference():
    a = np.array([1, 1, 1, 1, 0, 0, 1, 1, 0, 1], bool)
    b = np.array([1, 0, 0, 1, 0, 1, 1, 1, 0, 1], bool)
    assert discordant(a, b) == (2, 1) and mcnemar_z(2, 1) == pytest.approx(1 / np.sqrt(3))
    given = accuracy_difference(a, b)
    assert given["difference"] == pytest.approx(0.1) and given["n"] == 10
    variance = (3 - 1 / 10) / 100           # (b + c - (b - c)^2 / n) / n^2
    low, high = given["interval95"]
    assert high - low == pytest.approx(2 * 1.959964 * np.sqrt(variance), rel=1e-6)
    same = accuracy_difference(a, a)
    assert same["difference"] == 0 and same["interval95"] == [0, 0] and same["z"] == 0


@pytest.mark.parametrize("errors", [0, 1, 3, 4, 9])
def test_no_classifier_beats_the_reachable_z(errors):
    """The best any candidate can do against one wrong on `errors` rows is right on those and no
    other: its z is sqrt(errors), significant at 1.96 from 4 errors on."""
    kept = np.arange(40) >= errors
    perfect = np.ones(40, bool)
    assert mcnemar_z(*discordant(perfect, kept)) == pytest.approx(best_reachable_z(errors))
    assert significantly_better(perfect, kept, 1.96) == (errors >= 4)
