"""Non-ideal behaviour of the capacitive 6 x 6 skin and its MUCA read-out. A scene runs only those it lists.

The ideal chain (data/scenes/capacitive6x6.py) is: contact loads -> vertical stress at each
Tx/Rx crossing through the cover -> closure of the dielectric gap -> parallel-plate capacitance
-> raw counts. The effects below sit in that chain at two places, on arrays over
(frames, rows, cols):

- material effects act on the gap closure `state["closure"]` (1 - d/d0) before the capacitance;
- reading effects act on the counts `state["counts"]` as the board reports them, in the order
  of the analogue path: the sensor's own spread, coupling between lines, drift, interference,
  noise, then the 16-bit conversion last.

Reading effects draw from their own random generator `rng` (data/scenes/contract.py). `state`
also holds `time_s` (frames,), `rest_counts` (rows, cols, the ideal reading without load) and
`frame_rate_hz`. Every parameter is a keyword with its unit in its name.

The scene feeds long recordings through in chunks of frames, so memory stays flat. What
belongs to the sensor rather than to a frame (a cell's gain, a line's hum phase, the creep
still pending) lives in `state["device"]`, a dict that persists from chunk to chunk: each
effect draws it once, under its own name, and the generator `rng` carries on between chunks.
"""
import numpy as np
from scipy.signal import lfilter

from common.errors import InputError

FULL_SCALE_COUNTS = 2**16 - 1   # the FT5316 reports 16-bit raw values (seed 001 sec. 2.3)


def _check(condition, message):
    if not condition:
        raise InputError(f"scene capacitive6x6: {message}")


def _device(state, key, draw):
    """The sensor's own value `key`, drawn once (first chunk) and kept for later chunks."""
    device = state["device"]
    if key not in device:
        device[key] = draw()
    return device[key]


# -- material effects -----------------------------------------------------------------------
def hysteresis(state, creep_fraction=0.15, time_constant_s=0.4):
    """Viscoelastic lag of the silicone: a standard linear solid (Zener, *Elasticity and
    Anelasticity of Metals*, 1948; Ferry, *Viscoelastic Properties of Polymers*, 1980, ch. 1).

    Under a stress history the strain has an instantaneous part (1 - creep_fraction) and a
    delayed part that relaxes towards the elastic value with time constant tau:
        closure = (1 - f) closure_elastic + f * lowpass_tau(closure_elastic),
    the low-pass a first-order recursion at the frame rate. Loading and unloading therefore
    follow different paths (the reading lags on the way up and lingers on the way down), which
    is the rate-dependent hysteresis of Dragon Skin / Ecoflex layers.
    """
    _check(0.0 <= creep_fraction <= 1.0 and time_constant_s > 0,
           f"hysteresis needs 0 <= creep_fraction <= 1 and time_constant_s > 0, got {creep_fraction}, {time_constant_s}")
    closure = state["closure"]
    alpha = 1.0 - np.exp(-1.0 / (state["frame_rate_hz"] * time_constant_s))
    # y[t] = y[t-1] + alpha (x[t] - y[t-1]), from rest (closure 0) or where the last chunk ended
    # the filter's state is (1 - alpha) y[t-1]: zero at rest, then whatever the last chunk left
    pending = _device(state, "hysteresis", lambda: np.zeros((1,) + closure.shape[1:]))
    lagged, state["device"]["hysteresis"] = lfilter([alpha], [1.0, alpha - 1.0], closure, axis=0, zi=pending)
    state["closure"] = (1.0 - creep_fraction) * closure + creep_fraction * lagged


# -- reading effects ------------------------------------------------------------------------
def fabrication_spread(state, rng, gain_spread=0.08, offset_counts=40.0):
    """Hand-made cells differ (seed 001 sec. 2.4.3: "variations in the amount and shape of
    conductive material across sensing nodes"): each crossing gets its own sensitivity gain
    ~ N(1, gain_spread) on its change from rest, and its own rest offset ~ N(0, offset_counts).
    Drawn once per sensor (per scene seed)."""
    _check(gain_spread >= 0 and offset_counts >= 0,
           f"fabrication_spread needs gain_spread >= 0 and offset_counts >= 0, got {gain_spread}, {offset_counts}")
    rest = state["rest_counts"]
    gain, offset = _device(state, "fabrication_spread", lambda: (
        np.maximum(1.0 + gain_spread * rng.standard_normal(rest.shape), 0.0), offset_counts * rng.standard_normal(rest.shape)))
    state["counts"] = rest + gain * (state["counts"] - rest) + offset
    state["rest_counts"] = rest + offset


def crosstalk(state, rng, rx_coupling=0.03, tx_coupling=0.03):
    """Coupling between neighbouring electrode lines: a share of a crossing's change in charge
    appears on the crossings of the adjacent Rx lines (rows) and Tx lines (columns). Parallel
    yarns a few millimetres apart in silicone form a stray capacitance that carries it."""
    _check(0 <= rx_coupling < 0.25 and 0 <= tx_coupling < 0.25,
           f"crosstalk needs couplings in [0, 0.25), got {rx_coupling}, {tx_coupling}")
    change = state["counts"] - state["rest_counts"]
    leak = np.zeros_like(change)
    leak[:, 1:, :] += rx_coupling * change[:, :-1, :]
    leak[:, :-1, :] += rx_coupling * change[:, 1:, :]
    leak[:, :, 1:] += tx_coupling * change[:, :, :-1]
    leak[:, :, :-1] += tx_coupling * change[:, :, 1:]
    state["counts"] = state["counts"] + leak


def drift(state, rng, common_counts_per_min=3.0, cell_counts=4.0, period_range_s=(60.0, 600.0)):
    """Slow baseline drift (temperature, moisture in the silicone, the yarns relaxing): a common
    ramp ~ N(0, common_counts_per_min) per minute over the whole array plus, per cell, a slow
    sinusoid of amplitude ~ U(0.5, 1) * cell_counts and a period drawn from period_range_s.
    A baseline taken once at the start no longer fits later frames (the public code's weakness)."""
    low, high = period_range_s
    _check(common_counts_per_min >= 0 and cell_counts >= 0 and 0 < low <= high,
           f"drift needs non-negative amplitudes and 0 < period_range_s[0] <= [1], got "
           f"{common_counts_per_min}, {cell_counts}, {list(period_range_s)}")
    t = state["time_s"][:, None, None]
    shape = state["rest_counts"].shape
    rate, amplitude, period, phase = _device(state, "drift", lambda: (
        common_counts_per_min * rng.standard_normal() / 60.0, cell_counts * rng.uniform(0.5, 1.0, shape),
        rng.uniform(low, high, shape), rng.uniform(0.0, 2.0 * np.pi, shape)))
    wander = amplitude * (np.sin(2.0 * np.pi * t / period + phase) - np.sin(phase))
    state["counts"] = state["counts"] + rate * t + wander


def interference(state, rng, mains_hz=50.0, mains_counts=1.0, burst_probability=0.0, burst_counts=25.0):
    """Mains hum and EMI bursts picked up by the receive lines (the board is unshielded; seed 001
    mentions environmental electrostatic effects, and its refined design adds EMI shielding).

    Mains: each Rx line (row) sees mains_counts * w_i * sin(2 pi f t + phi_i), w_i ~ U(0.5, 1);
    sampled at the frame rate (60 Hz) a 50 Hz hum aliases to a 10 Hz beat. Bursts: with
    burst_probability per frame one random Rx line jumps by +/- burst_counts * U(0.5, 1).
    """
    _check(mains_hz >= 0 and mains_counts >= 0 and 0 <= burst_probability <= 1 and burst_counts >= 0,
           f"interference needs non-negative mains_hz, mains_counts, burst_counts and a probability "
           f"in [0, 1], got {mains_hz}, {mains_counts}, {burst_probability}, {burst_counts}")
    counts = state["counts"]
    n_frames, n_rows, _ = counts.shape
    weight, phase = _device(state, "interference", lambda: (rng.uniform(0.5, 1.0, n_rows),
                                                            rng.uniform(0.0, 2.0 * np.pi, n_rows)))
    hum = mains_counts * weight * np.sin(2.0 * np.pi * mains_hz * state["time_s"][:, None] + phase)
    counts = counts + hum[:, :, None]
    if burst_probability > 0:
        hit = rng.random(n_frames) < burst_probability
        line = rng.integers(0, n_rows, n_frames)
        size = burst_counts * rng.uniform(0.5, 1.0, n_frames) * rng.choice([-1.0, 1.0], n_frames)
        frames = np.flatnonzero(hit)
        counts[frames, line[frames], :] += size[frames, None]
    state["counts"] = counts


def baseline_noise(state, rng, noise_counts=1.6):
    """White noise of the charge amplifier and ADC on every cell and frame, N(0, noise_counts).
    The default puts the limit of detection (3 sigma of one frame) near 0.1 N, seed 001 sec. 3.4."""
    _check(noise_counts >= 0, f"baseline_noise needs noise_counts >= 0, got {noise_counts}")
    state["counts"] = state["counts"] + noise_counts * rng.standard_normal(state["counts"].shape)


def quantisation(state, rng, full_scale_counts=FULL_SCALE_COUNTS):
    """The controller reports integers in [0, full scale] (16 bit): rounding, and saturation at
    both ends of the scale."""
    _check(full_scale_counts >= 1, f"quantisation needs full_scale_counts >= 1, got {full_scale_counts}")
    state["counts"] = np.clip(np.rint(state["counts"]), 0.0, float(full_scale_counts))


MATERIAL_EFFECTS = {"hysteresis": hysteresis}
READING_EFFECTS = {"fabrication_spread": fabrication_spread, "crosstalk": crosstalk, "drift": drift,
                   "interference": interference, "baseline_noise": baseline_noise, "quantisation": quantisation}
EFFECTS = {**MATERIAL_EFFECTS, **READING_EFFECTS}
