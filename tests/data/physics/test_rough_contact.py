"""Property tests for the fingertip's new numeric physics: Persson real contact area
(data/physics/rough_contact.py), spring-block stick-slip (data/physics/stick_slip.py) and the FSR
amplifier readout and its inverse (data/physics/force_sensing_resistor.py)."""
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from common.errors import InputError
from data.physics.force_sensing_resistor import (
    FsrCalibration,
    amplifier_voltage_v,
    fsr_force_n,
)
from data.physics.rough_contact import (
    contact_modulus_pa,
    real_contact_fraction,
    rms_slope,
    surface_profile,
)
from data.physics.stick_slip import slip_length_mm, stick_slip_cycle

heights = st.floats(0.001, 50.0)
hursts = st.floats(0.05, 0.95)
moduli = st.floats(1e4, 1e11)
slopes = st.floats(1e-6, 2.0)


@given(st.lists(st.floats(0.0, 1e7), min_size=2, max_size=20), moduli, slopes)
def test_real_contact_is_monotone_in_load_and_bounded_by_the_nominal_area(pressures, modulus, slope):
    p = np.sort(np.asarray(pressures))
    a = real_contact_fraction(p, modulus, slope)
    assert np.isfinite(a).all() and (a >= 0).all() and (a <= 1).all()
    assert (np.diff(a) >= 0).all()


def test_no_load_no_contact_and_light_load_is_linear():
    assert real_contact_fraction(0.0, 1e6, 0.01) == 0.0
    assert real_contact_fraction(-5.0, 1e6, 0.01) == 0.0       # a pull is no contact, not NaN
    light = real_contact_fraction([10.0, 20.0], 1e6, 0.01)     # p0 << E* h'
    assert light[1] == pytest.approx(2 * light[0], rel=1e-3)
    assert light[0] == pytest.approx(np.sqrt(8 / np.pi) * 10.0 / (1e6 * 0.01), rel=1e-3)   # Persson's small-load limit
    assert real_contact_fraction(1e9, 1e6, 0.01) == pytest.approx(1.0)


@given(heights, hursts)
def test_rms_slope_is_proportional_to_rms_height(height, hurst):
    s1 = rms_slope(height, hurst, 1.0, 0.02)
    assert s1 > 0 and rms_slope(2 * height, hurst, 1.0, 0.02) == pytest.approx(2 * s1, rel=1e-9)
    assert rms_slope(height, hurst, 1.0, 0.01) > s1            # a finer cutoff adds slope


def test_a_rougher_surface_saturates_later():
    smooth, rough = rms_slope(0.05, 0.8, 2.0, 0.02), rms_slope(20.0, 0.8, 2.0, 0.02)
    p = np.array([2e3, 5e4])
    assert (real_contact_fraction(p, 1e6, smooth) > real_contact_fraction(p, 1e6, rough)).all()
    assert real_contact_fraction(5e4, 1e6, smooth) > 0.99 and real_contact_fraction(5e4, 1e6, rough) < 0.5


@given(st.integers(0, 10_000), hursts, st.floats(0.3, 5.0))
def test_surface_profile_has_unit_rms_and_is_reproducible(seed, hurst, roll_off):
    a = surface_profile(np.random.default_rng(seed), 100.0, 0.05, hurst, roll_off, 0.02)
    b = surface_profile(np.random.default_rng(seed), 100.0, 0.05, hurst, roll_off, 0.02)
    assert a.shape == (2000,) and np.isfinite(a).all()
    assert a.std() == pytest.approx(1.0, rel=0.02)
    np.testing.assert_array_equal(a, b)


def test_contact_modulus_combines_compliances():
    assert contact_modulus_pa((1e6, 0.5)) == pytest.approx(1e6 / 0.75)
    assert contact_modulus_pa((1e6, 0.5), (70e9, 0.22)) == pytest.approx(1e6 / 0.75, rel=1e-4)   # glass ~ rigid


@pytest.mark.parametrize("call, message", [
    (lambda: contact_modulus_pa((-1e6, 0.3)), "modulus must be positive"),
    (lambda: rms_slope(1.0, 1.2, 1.0, 0.02), "hurst_exponent"),
    (lambda: rms_slope(-1.0, 0.8, 1.0, 0.02), "rms_height_um"),
    (lambda: rms_slope(1.0, 0.8, 0.01, 0.02), "shorter than the roll-off"),
    (lambda: slip_length_mm(1.0, 0.3, -0.1, 5.0), "must be >= 0"),
    (lambda: slip_length_mm(1.0, 0.2, 0.3, 5.0), "static friction"),
    (lambda: slip_length_mm(1.0, 0.4, 0.3, 0.0), "tangential stiffness"),
    (lambda: amplifier_voltage_v(5.0, reference_v=4.0), "reference_v"),
])
def test_impossible_parameters_are_one_line_errors(call, message):
    with pytest.raises(InputError, match=message):
        call()


@given(st.floats(0.0, 50.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.1, 50.0),
       st.lists(st.floats(0.0, 200.0), min_size=1, max_size=30))
def test_stick_slip_lag_stays_within_one_slip(force, mu_a, mu_b, stiffness, travel):
    static, kinetic = max(mu_a, mu_b), min(mu_a, mu_b)
    slip = slip_length_mm(force, static, kinetic, stiffness)
    assert slip == pytest.approx(2 * (static - kinetic) * force / stiffness)
    phase, lag = stick_slip_cycle(np.asarray(travel), slip)
    assert np.isfinite(lag).all() and (phase >= 0).all() and (phase < 1).all()
    assert (lag >= 0).all() and (lag <= slip + 1e-12).all()


def test_stick_slip_period_grows_with_load():
    assert slip_length_mm(25.0, 0.5, 0.4, 5.0) == pytest.approx(25 * slip_length_mm(1.0, 0.5, 0.4, 5.0))
    assert slip_length_mm(10.0, 0.4, 0.4, 5.0) == 0.0          # equal coefficients: steady sliding


@given(st.floats(0.3, 60.0))
def test_amplifier_calibration_inverts_the_readout(force):
    volts = amplifier_voltage_v(force)
    assert 0.25 < volts < 3.3                                  # never reaches the rail
    assert fsr_force_n(volts) == pytest.approx(force, rel=1e-6)


def test_amplifier_spreads_the_high_forces_and_reads_no_load_as_zero():
    volts = amplifier_voltage_v([0.0, 1.0, 10.0, 25.0])
    assert volts[3] - volts[2] > 0.5                           # 10-25 N over > 0.5 V (a divider gave 160 mV)
    assert fsr_force_n(volts[0]) < 1e-3 and fsr_force_n(0.0) == 0.0
    assert FsrCalibration()(__import__("torch").tensor([3.3], dtype=__import__("torch").float64)).item() <= 66.0


def test_combs_read_a_uniform_pattern_as_nothing_and_select_their_period():
    from data.physics.comb_electrodes import comb_differential
    step, period, length = 0.05, 2.0, 20.0
    x = np.arange(4000) * step
    assert np.abs(comb_differential(np.ones_like(x), step, period, length)).max() < 1e-9
    at_period = comb_differential(np.sin(2 * np.pi * x / period), step, period, length)
    assert np.abs(at_period).max() == pytest.approx(2 / np.pi, rel=0.02)
    off_period = comb_differential(np.sin(2 * np.pi * x / 7.0), step, period, length)
    assert np.abs(off_period).max() < 0.1 * np.abs(at_period).max()
    with pytest.raises(InputError, match="shorter than the pad"):
        comb_differential(np.ones(10), step, period, length)
