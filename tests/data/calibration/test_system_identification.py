"""The fit recovers hidden parameters of a rig stand-in (the scene moved by up to 40 % with its
unmodelled noise and quantisation on) within the 95 % interval it reports; readings of the wrong
unit or sign stop it with one line naming the channel and the ratio; fewer presses than
parameters are refused; the fitted scene keeps every listed effect."""
import numpy as np
import pytest
from hydra.utils import instantiate

from common.errors import InputError
from data.calibration.identifiable import get_value
from data.calibration.rig_standin import hidden_parameters, rig_presses
from data.calibration.system_identification import identify

Z95 = 1.96


@pytest.fixture
def taxels(compose_config):
    scene = instantiate(compose_config(["scene=taxels"]).scene)
    hidden = hidden_parameters(scene, np.random.default_rng(11))
    return scene, hidden, rig_presses(scene, hidden, 11, 120)


def test_hidden_parameters_are_recovered_within_the_reported_interval(taxels):
    scene, hidden, presses = taxels
    fit, fitted_scene = identify(scene, presses, max_evaluations=60)
    for p in fit.parameters:
        assert not p.at_bound and p.sd > 0, p
        low, high = p.interval()
        assert low <= hidden[p.path] <= high, (p.path, p.value, p.sd, hidden[p.path])
        if p.log:   # the interval is symmetric on the log scale, so it never reaches 0
            assert low > 0 and low * high == pytest.approx(p.value**2)
        else:
            assert (low, high) == pytest.approx((p.value - Z95 * p.sd, p.value + Z95 * p.sd), rel=1e-3)
        assert get_value(fitted_scene, p.path) == p.value
        moved = abs(hidden[p.path] - p.default)
        assert abs(p.value - hidden[p.path]) < max(moved, Z95 * p.sd)   # closer than the scene's own value, or within noise
    assert set(fitted_scene.effects) == set(scene.effects)              # the unmodelled effects are kept
    assert fit.notes["noise"][:2] == ("noise", "rms_mv") and 1.0 < fit.notes["noise"][2] < 5.0   # the rig's 2.5 mV
    assert np.mean(list(fit.residual_rms.values())) < np.mean(list(fit.default_residual_rms.values()))


@pytest.mark.parametrize("scale, shown", [(1e-3, "0.001"), (-1.0, "-1")])
def test_readings_of_another_unit_or_sign_stop_the_fit_naming_the_channel(taxels, scale, shown):
    scene, _, presses = taxels
    channels = [c for c in presses.columns if c.endswith("_mv")]
    presses = presses.copy()
    presses[channels] *= scale
    with pytest.raises(InputError, match=r"channel 'v_t\d_\w+_mv' reads -?[\d.e-]+ x the (change|level) scene taxels "
                                         r"simulates .* check the channel's unit and sign convention") as error:
        identify(scene, presses, max_evaluations=15)
    assert "\n" not in str(error.value)


def test_fewer_presses_than_parameters_are_refused(taxels):
    scene, _, presses = taxels
    with pytest.raises(InputError, match="needs at least 3 presses .* got 2"):
        identify(scene, presses.iloc[:2], max_evaluations=5)
