"""Effects of the fingertip scene. A scene runs only those it lists.

Source effects act on the force and charge before the two channels are synthesised; reading
effects act on the synthesised channels (triboelectric current in nA, piezoresistive divider
voltage in V). Arrays are (n_recordings, n_timesteps); each function draws from its own
random stream `rng`.
"""
import numpy as np

from data.scenes.fingertip_boards import ridge_profile
from data.errors import InputError


# -- source effects -------------------------------------------------------------------------
def force_ripple(state, rng, amplitude=0.08):
    """Texture-induced force modulation while sliding: ridges passing under the cushion push it
    up and down, F <- F (1 + amplitude (2 c(x / period) - 1)), at v / period. Flat boards: none."""
    profile, period = state["profile"], state["period_mm"]
    ridged = period > 0
    if not ridged.any():
        return
    c = np.zeros_like(state["force_n"])
    for name in np.unique(profile[ridged]):
        rows = profile == name
        c[rows] = ridge_profile(name, state["position_mm"][rows] / period[rows, None])
    sliding = state["sliding"]
    state["force_n"] = state["force_n"] * np.where(ridged[:, None] & sliding, 1.0 + amplitude * (2 * c - 1), 1.0)


def humidity(state, rng, relative_humidity_pct=45.0, spread_pct=5.0, reference_pct=30.0, decay_pct=50.0):
    """Surface charge falls as humidity rises (a water film bleeds charge away; physics notes):
    sigma <- sigma exp(-(RH - RH_ref) / decay). Each recording gets RH ~ U(RH +/- spread)."""
    rh = relative_humidity_pct + rng.uniform(-spread_pct, spread_pct, size=len(state["sigma_uc_m2"]))
    state["relative_humidity_pct"] = rh
    state["sigma_uc_m2"] = state["sigma_uc_m2"] * np.exp(-(rh - reference_pct) / decay_pct)


# -- reading effects ------------------------------------------------------------------------
def electrostatic_noise(state, rng, mains_hz=50.0, hum_na=2.0, broadband_na=1.0, piezo_noise_v=0.002):
    """Pick-up on the high-impedance triboelectric line: mains hum at a random phase per
    recording plus white noise; a little white noise on the divider voltage too."""
    current = state["triboelectric_na"]
    t = state["time_s"][None, :]
    phase = rng.uniform(0, 2 * np.pi, size=(len(current), 1))
    state["triboelectric_na"] = (current + hum_na * np.sin(2 * np.pi * mains_hz * t + phase)
                                 + broadband_na * rng.standard_normal(current.shape))
    state["piezoresistive_v"] = state["piezoresistive_v"] + piezo_noise_v * rng.standard_normal(current.shape)


def adc(state, rng, bits=12, supply_v=3.3, transimpedance_v_per_na=0.005):
    """Both channels through an N-bit ADC over 0..supply: the current via a transimpedance stage
    centred at mid-rail (+/- 330 nA at the default gain), the divider voltage directly. Values
    outside the range clip, as a real ADC does."""
    if bits < 1:
        raise InputError(f"scene fingertip: adc needs bits >= 1, got {bits}")
    lsb = supply_v / (2**bits - 1)

    def quantise(volts):
        return np.clip(np.rint(volts / lsb), 0, 2**bits - 1) * lsb

    mid = supply_v / 2
    state["triboelectric_na"] = (quantise(mid + transimpedance_v_per_na * state["triboelectric_na"]) - mid) \
        / transimpedance_v_per_na
    state["piezoresistive_v"] = quantise(state["piezoresistive_v"])


SOURCE_EFFECTS = {"force_ripple": force_ripple, "humidity": humidity}
READING_EFFECTS = {"electrostatic_noise": electrostatic_noise, "adc": adc}
EFFECTS = {**SOURCE_EFFECTS, **READING_EFFECTS}
