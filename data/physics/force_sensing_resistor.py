"""A force-sensing resistor (Interlink FSR 400 series) read through a non-inverting amplifier.

The film (Interlink FSR 400 series integration guide): open (> 10 MOhm) below the actuation
force, R = R_1N F^-n above it (n ~ 0.7-1, conductance about linear in force), with a soft
saturation of the effective force near the top of the 0.2-20 N range,
F_eff = F / (1 + (F / F_sat)^4)^(1/4).

The readout is the seed paper's (sec. 2.3, Fig. 1c): "a non-inverting proportional amplifier"
built on an RS8524 op-amp with "a 1 kOhm charging resistor in the inverting input", output
0-3.3 V. We read it as the standard FSR gain stage (Interlink FSR integration guide, "FSR
voltage / current conversion"; Horowitz & Hill, *The Art of Electronics*, 3rd ed. 2015, sec.
4.2.3): a small reference V_ref on the non-inverting input, a feedback resistor R_f, and the
film in series with the 1 kOhm resistor R_s from the inverting input to ground, so

    V = V_ref (1 + R_f / (R_FSR + R_s)),    clipped to the rail-to-rail output range 0..V_supply.

The gain is proportional to the film's conductance, hence about linear in force, and R_s bounds
it when the film's resistance falls at high force. V_ref and R_f are not given in the paper:
V_ref = 0.25 V and R_f = 18 kOhm are our estimates, chosen so that the film's lowest resistance
(at saturation) stays below the 3.3 V rail: 1 N reads 0.66 V, 10 N 2.24 V, 25 N 2.91 V.

Inverse (the calibration a user does with a load cell, paper sec. 4.1): volts -> newtons. It
exists once, as a torch module, so that training (on numpy arrays, through `fsr_force_n`) and the
exported ONNX graph (on tensors) run the same arithmetic with the same constants.
"""
import numpy as np
import torch
from torch import nn

from common.errors import InputError

# The one table of the amplifier's and film's defaults: the scene, the calibration and the
# exported graph all start from these.
AMPLIFIER_DEFAULTS = {"supply_v": 3.3, "reference_v": 0.25, "feedback_resistor_ohm": 1.8e4,
                      "series_resistor_ohm": 1.0e3}
FILM_DEFAULTS = {"fsr_resistance_1n_ohm": 1.0e4, "fsr_exponent": 0.9, "fsr_saturation_n": 22.0}
CALIBRATION_KEYS = tuple(AMPLIFIER_DEFAULTS) + tuple(FILM_DEFAULTS)


def check_readout(**parameters) -> dict:
    p = {**AMPLIFIER_DEFAULTS, **FILM_DEFAULTS, **parameters}
    for key in CALIBRATION_KEYS:
        if not np.isfinite(p[key]) or p[key] <= 0:
            raise InputError(f"FSR readout: {key} must be positive, got {p[key]}")
    if p["reference_v"] >= p["supply_v"]:
        raise InputError(f"FSR readout: reference_v ({p['reference_v']} V) must lie below supply_v ({p['supply_v']} V)")
    return p


def film_resistance_ohm(force_n, fsr_actuation_n=0.2, fsr_open_ohm=1.0e7, **parameters) -> np.ndarray:
    """The film's resistance for a force in newtons (array-like): the forward law."""
    p = {**FILM_DEFAULTS, **parameters}
    force = np.asarray(force_n, dtype=np.float64)
    ratio_squared = np.square(force / p["fsr_saturation_n"])
    # F / (1 + (F / F_sat)^4)^(1/4), with squares and square roots: a general power costs 5x more
    effective = force / np.sqrt(np.sqrt(1.0 + np.square(ratio_squared)))
    # R_1N F_eff^-n = R_1N exp(-n ln F_eff)
    resistance = p["fsr_resistance_1n_ohm"] * np.exp(-p["fsr_exponent"] * np.log(np.maximum(effective, 1e-12)))
    return np.where(force >= fsr_actuation_n, np.minimum(resistance, fsr_open_ohm), fsr_open_ohm)


def amplifier_voltage_v(force_n, fsr_actuation_n=0.2, fsr_open_ohm=1.0e7, **parameters) -> np.ndarray:
    """Amplifier output for a force in newtons: V_ref (1 + R_f / (R_FSR + R_s)), clipped to the rails."""
    p = check_readout(**parameters)
    resistance = film_resistance_ohm(force_n, fsr_actuation_n, fsr_open_ohm,
                                     **{k: p[k] for k in FILM_DEFAULTS})
    volts = p["reference_v"] * (1.0 + p["feedback_resistor_ohm"] / (resistance + p["series_resistor_ohm"]))
    return np.minimum(volts, p["supply_v"])


class FsrCalibration(nn.Module):
    """volts -> newtons: R = R_f / (V / V_ref - 1) - R_s, F_eff = (R_1N / R)^(1/n), then undo the
    soft saturation, F = F_eff / (1 - (F_eff / F_sat)^4)^(1/4). Readings at or beyond saturation
    (R <= 0 or F_eff >= F_sat) are capped at 3 F_sat; at or below V_ref (an open film) read 0 N.
    Constants are float64 buffers: a Python scalar passes through float32 in the ONNX exporter
    (1e-12 became 9.99999996e-13)."""

    def __init__(self, supply_v=AMPLIFIER_DEFAULTS["supply_v"], reference_v=AMPLIFIER_DEFAULTS["reference_v"],
                 feedback_resistor_ohm=AMPLIFIER_DEFAULTS["feedback_resistor_ohm"],
                 series_resistor_ohm=AMPLIFIER_DEFAULTS["series_resistor_ohm"],
                 fsr_resistance_1n_ohm=FILM_DEFAULTS["fsr_resistance_1n_ohm"],
                 fsr_exponent=FILM_DEFAULTS["fsr_exponent"], fsr_saturation_n=FILM_DEFAULTS["fsr_saturation_n"]):
        super().__init__()
        check_readout(supply_v=supply_v, reference_v=reference_v, feedback_resistor_ohm=feedback_resistor_ohm,
                      series_resistor_ohm=series_resistor_ohm, fsr_resistance_1n_ohm=fsr_resistance_1n_ohm,
                      fsr_exponent=fsr_exponent, fsr_saturation_n=fsr_saturation_n)
        constants = {"supply_v": supply_v, "reference_v": reference_v, "feedback_ohm": feedback_resistor_ohm,
                     "series_ohm": series_resistor_ohm, "resistance_1n_ohm": fsr_resistance_1n_ohm,
                     "inverse_exponent": 1.0 / fsr_exponent, "saturation_n": fsr_saturation_n,
                     "ratio_cap": 1 - 1e-6, "force_cap_n": 3 * fsr_saturation_n, "gain_floor": 1e-12,
                     "ohm_floor": 1e-9, "zero": 0.0}
        for name, value in constants.items():
            self.register_buffer(name, torch.tensor(value, dtype=torch.float64))

    def forward(self, volts: torch.Tensor) -> torch.Tensor:
        v = torch.minimum(torch.maximum(volts.double(), self.zero), self.supply_v)
        gain = v / self.reference_v - 1.0
        resistance = self.feedback_ohm / torch.maximum(gain, self.gain_floor) - self.series_ohm
        effective = (self.resistance_1n_ohm / torch.maximum(resistance, self.ohm_floor)) ** self.inverse_exponent
        ratio = torch.minimum(effective / self.saturation_n, self.ratio_cap)
        force = torch.minimum(effective / (1.0 - ratio ** 4) ** 0.25, self.force_cap_n)
        return torch.where(gain > 0, force, torch.zeros_like(force))


def fsr_force_n(volts, **parameters) -> np.ndarray:
    """FsrCalibration on a numpy array (float64 in, float64 out)."""
    with torch.no_grad():
        return FsrCalibration(**parameters)(torch.from_numpy(np.asarray(volts, dtype=np.float64))).numpy()


def calibrated_channel_name(channel: str, renamed: str | None = None) -> str:
    """The name a calibrated channel takes: its unit becomes newtons (piezoresistive_v ->
    piezoresistive_n) unless the config renames it."""
    return renamed or channel.rsplit("_", 1)[0] + "_n"
