"""A force-sensing resistor (Interlink FSR 400 series) read through a voltage divider.

Forward (the fingertip scene): open (> 10 MOhm) below the actuation force, R = R_1N F^-n
above it (n ~ 0.7-1, conductance about linear in force), with a soft saturation of the
effective force near the top of the 0.2-20 N range, F_eff = F / (1 + (F / F_sat)^4)^(1/4),
read as V = V_s R_m / (R_m + R) (Interlink FSR 400 integration guide).

Inverse (the calibration a user does with a load cell): volts -> newtons. It exists once, as
a torch module, so that training (on numpy arrays, through `fsr_force_n`) and the exported
ONNX graph (on tensors) run the same arithmetic with the same constants.
"""
import numpy as np
import torch
from torch import nn

# The one table of the divider's and film's defaults: the scene, the calibration and the
# exported graph all start from these.
DIVIDER_DEFAULTS = {"supply_v": 3.3, "divider_resistor_ohm": 1.0e4}
FILM_DEFAULTS = {"fsr_resistance_1n_ohm": 1.0e4, "fsr_exponent": 0.9, "fsr_saturation_n": 22.0}
CALIBRATION_KEYS = tuple(DIVIDER_DEFAULTS) + tuple(FILM_DEFAULTS)


def divider_voltage_v(force_n, fsr_actuation_n=0.2, fsr_open_ohm=1.0e7, **parameters) -> np.ndarray:
    """Divider voltage for a force in newtons (array-like), the film's forward law."""
    p = {**DIVIDER_DEFAULTS, **FILM_DEFAULTS, **parameters}
    force = np.asarray(force_n, dtype=np.float64)
    effective = force / (1.0 + (force / p["fsr_saturation_n"]) ** 4) ** 0.25
    resistance = np.where(force >= fsr_actuation_n,
                          np.minimum(p["fsr_resistance_1n_ohm"] * np.maximum(effective, 1e-12) ** -p["fsr_exponent"],
                                     fsr_open_ohm),
                          fsr_open_ohm)
    return p["supply_v"] * p["divider_resistor_ohm"] / (p["divider_resistor_ohm"] + resistance)


class FsrCalibration(nn.Module):
    """volts -> newtons: R = R_m (V_s - V) / V, F_eff = (R_1N / R)^(1/n), then undo the soft
    saturation, F = F_eff / (1 - (F_eff / F_sat)^4)^(1/4). Readings at or beyond saturation are
    capped at 3 F_sat; 0 V reads 0 N. Constants are float64 buffers: a Python scalar passes
    through float32 in the ONNX exporter (1e-12 became 9.99999996e-13)."""

    def __init__(self, supply_v=DIVIDER_DEFAULTS["supply_v"],
                 divider_resistor_ohm=DIVIDER_DEFAULTS["divider_resistor_ohm"],
                 fsr_resistance_1n_ohm=FILM_DEFAULTS["fsr_resistance_1n_ohm"],
                 fsr_exponent=FILM_DEFAULTS["fsr_exponent"], fsr_saturation_n=FILM_DEFAULTS["fsr_saturation_n"]):
        super().__init__()
        constants = {"top_v": supply_v * (1 - 1e-9), "supply_v": supply_v, "divider_ohm": divider_resistor_ohm,
                     "resistance_1n_ohm": fsr_resistance_1n_ohm, "inverse_exponent": 1.0 / fsr_exponent,
                     "saturation_n": fsr_saturation_n, "ratio_cap": 1 - 1e-6, "force_cap_n": 3 * fsr_saturation_n,
                     "volt_floor": 1e-12, "zero": 0.0}
        for name, value in constants.items():
            self.register_buffer(name, torch.tensor(value, dtype=torch.float64))

    def forward(self, volts: torch.Tensor) -> torch.Tensor:
        v = torch.minimum(torch.maximum(volts.double(), self.zero), self.top_v)
        resistance = self.divider_ohm * (self.supply_v - v) / torch.maximum(v, self.volt_floor)
        effective = (self.resistance_1n_ohm / resistance) ** self.inverse_exponent
        ratio = torch.minimum(effective / self.saturation_n, self.ratio_cap)
        force = torch.minimum(effective / (1.0 - ratio ** 4) ** 0.25, self.force_cap_n)
        return torch.where(v > 0, force, torch.zeros_like(force))


def fsr_force_n(volts, **parameters) -> np.ndarray:
    """FsrCalibration on a numpy array (float64 in, float64 out)."""
    with torch.no_grad():
        return FsrCalibration(**parameters)(torch.from_numpy(np.asarray(volts, dtype=np.float64))).numpy()


def calibrated_channel_name(channel: str, renamed: str | None = None) -> str:
    """The name a calibrated channel takes: its unit becomes newtons (piezoresistive_v ->
    piezoresistive_n) unless the config renames it."""
    return renamed or channel.rsplit("_", 1)[0] + "_n"
