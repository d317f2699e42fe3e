"""Conformal intervals for the ERT learned inverse: calibration recordings must be independent
of the recording the Tikhonov reconstruction was fitted on, and recordings (not presses) are the
exchangeable units."""
import numpy as np
import pytest

from common.errors import InputError
from data.scenes.ert import ERTScene
from models.uncertainty import conformal_quantile, leave_one_group_out_coverage

BOUNDARY = [[x, 200.0] for x in (50, 150)] + [[200.0, y] for y in (50, 150)] + \
           [[x, 0.0] for x in (150, 50)] + [[0.0, y] for y in (50, 150)]
EFFECTS = {"contact_resistance": {}, "hysteresis": {}, "baseline_drift": {}, "adc_noise": {}}


def _scene(**kw):
    return ERTScene(electrodes_mm=BOUNDARY, grid_nodes=21, injection="adjacent", effects=EFFECTS,
                    protocol="calibration", grid_points_per_side=3, n_force_levels=2, seed=3, **kw)


def test_session_zero_is_the_plain_recording_and_later_sessions_draw_anew():
    plain, zero = _scene().generate(), _scene(session=0).generate()
    one, two = _scene(session=1).generate(), _scene(session=2).generate()
    assert np.array_equal(plain.channels, zero.channels)
    assert np.array_equal(plain.targets, one.targets)           # the same presses ...
    for a, b in ((zero, one), (one, two), (zero, two)):         # ... with their own noise and drift
        assert not np.allclose(a.channels, b.channels)
    assert np.array_equal(one.channels, _scene(session=1).generate().channels)   # and seeded


def test_a_negative_session_is_bad_input():
    with pytest.raises(InputError, match="session must be >= 0"):
        _scene(session=-1).generate()


def test_leave_one_group_out_coverage_is_nominal_for_exchangeable_groups_and_flags_a_shifted_one():
    rng = np.random.default_rng(0)
    groups = np.repeat(np.arange(6), 400)
    scores = np.abs(rng.normal(size=(len(groups), 2)))
    loo = leave_one_group_out_coverage(scores, groups, alpha=0.05)
    assert loo.shape == (6, 2) and abs(loo.mean() - 0.95) < 0.015
    scores[groups == 5] *= 3.0                                  # one recording far noisier
    shifted = leave_one_group_out_coverage(scores, groups, alpha=0.05)
    assert shifted[5].max() < 0.75 and shifted[:5].min() > 0.95
    # each entry is the share within the other groups' conformal quantile
    q = conformal_quantile(scores[groups != 0], 0.05)
    assert np.allclose(shifted[0], (scores[groups == 0] <= q).mean(axis=0))
    with pytest.raises(InputError, match="at least 2 groups"):
        leave_one_group_out_coverage(scores, np.zeros(len(groups)), alpha=0.05)
