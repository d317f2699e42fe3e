"""Scene `fingertip`: a hybrid triboelectric + piezoresistive fingertip sliding over boards.

Sensor (seed 003): a 20 x 23 mm fingertip (silicone cushion, FSR402-like piezoresistive
film, interdigitated copper grating electrodes under a Kapton triboelectric layer). A robot
moves it along a trapezoidal track: down a 30 deg incline until it touches the board and
the cushion compresses to the force level, across the board, and back up at 30 deg. Each
pass is one recording of two channels at 250 Hz: `triboelectric_na` (short-circuit current)
and `piezoresistive_v` (the FSR's divider voltage, 0-3.3 V). Protocol: every board x force
level {1, 5, 10, 15, 20, 25} N x 15 passes; each pass starts at a random phase of the texture.

Triboelectric channel (Niu et al., Adv. Mater. 25, 2013; Niu & Wang, Nano Energy 14, 2015):
the current is the rate of change of the charge induced on the electrodes,
    Q = sigma A x / (d0 + x)                      contact-separation (gap x, d0 = sum d_i/eps_ri)
      + eta sigma w period c(X / period)          sliding over ridges (c: ridge contact share)
so sliding at speed v gives I ~ sigma w v modulated at the fundamental v / period. On a flat
board the grating of the electrodes (period `grating_period_mm`) does the modulating, weakly
(`flat_efficiency`). Charge density grows with load, sigma = sigma_material (1 - exp(-F / F_c)),
roughly linear at low force (physics notes), which is why force confounds material.

Piezoresistive channel: an Interlink FSR 400-series film in a voltage divider
(data/physics/force_sensing_resistor.py).

Only listed effects run (data/scenes/fingertip_effects.py): source effects before the channels are
synthesised, reading effects after.
"""
import numpy as np
import pandas as pd

from data.scenes.fingertip_boards import CHARGE_DENSITY_UC_M2, parse_texture, resolve_boards, ridge_profile
from data.scenes.contract import random_generator_for, resolve_effects
from data.errors import InputError
from data.physics.force_sensing_resistor import DIVIDER_DEFAULTS, FILM_DEFAULTS, divider_voltage_v
from data.scenes.fingertip_effects import EFFECTS, READING_EFFECTS, SOURCE_EFFECTS
from data.recordings import RecordingSet

CHANNELS = ["triboelectric_na", "piezoresistive_v"]


class FingertipScene:
    name = "fingertip"

    def __init__(self, boards="combined18", force_levels_n=(1, 5, 10, 15, 20, 25), passes_per_level=15,
                 seed=0, effects=None, sample_rate_hz=250.0, slide_speed_mm_s=15.0, slide_length_mm=90.0,
                 base_angle_deg=30.0, approach_height_mm=2.0, idle_s=0.3, cushion_stiffness_n_per_mm=5.0,
                 fingertip_width_mm=20.0, fingertip_length_mm=23.0, dielectric_gap_mm=0.5,
                 sliding_efficiency=0.5, flat_efficiency=0.1, grating_period_mm=2.0,
                 charge_force_scale_n=15.0, charge_density_uc_m2=None,
                 fsr_actuation_n=0.2, fsr_resistance_1n_ohm=FILM_DEFAULTS["fsr_resistance_1n_ohm"],
                 fsr_exponent=FILM_DEFAULTS["fsr_exponent"], fsr_saturation_n=FILM_DEFAULTS["fsr_saturation_n"],
                 fsr_open_ohm=1.0e7, divider_resistor_ohm=DIVIDER_DEFAULTS["divider_resistor_ohm"],
                 supply_v=DIVIDER_DEFAULTS["supply_v"]):
        self.boards = boards
        self.force_levels_n = force_levels_n
        self.passes_per_level = passes_per_level
        self.seed = seed
        self.effects = effects
        self.sample_rate_hz = sample_rate_hz
        self.slide_speed_mm_s = slide_speed_mm_s
        self.slide_length_mm = slide_length_mm
        self.base_angle_deg = base_angle_deg
        self.approach_height_mm = approach_height_mm
        self.idle_s = idle_s
        self.cushion_stiffness_n_per_mm = cushion_stiffness_n_per_mm
        self.fingertip_width_mm = fingertip_width_mm
        self.fingertip_length_mm = fingertip_length_mm
        self.dielectric_gap_mm = dielectric_gap_mm
        self.sliding_efficiency = sliding_efficiency
        self.flat_efficiency = flat_efficiency
        self.grating_period_mm = grating_period_mm
        self.charge_force_scale_n = charge_force_scale_n
        self.charge_density_uc_m2 = charge_density_uc_m2
        self.fsr_actuation_n = fsr_actuation_n
        self.fsr_resistance_1n_ohm = fsr_resistance_1n_ohm
        self.fsr_exponent = fsr_exponent
        self.fsr_saturation_n = fsr_saturation_n
        self.fsr_open_ohm = fsr_open_ohm
        self.divider_resistor_ohm = divider_resistor_ohm
        self.supply_v = supply_v

    # -- protocol ---------------------------------------------------------------------------
    def _check(self):
        levels = np.asarray(self.force_levels_n, dtype=float)
        if levels.size == 0 or (levels <= 0).any():
            raise InputError(f"scene.force_levels_n must be positive newtons, got {list(self.force_levels_n)}")
        if not isinstance(self.passes_per_level, int) or self.passes_per_level < 1:
            raise InputError(f"scene.passes_per_level must be a positive integer, got {self.passes_per_level!r}")
        if min(self.slide_speed_mm_s, self.slide_length_mm, self.sample_rate_hz, self.cushion_stiffness_n_per_mm) <= 0:
            raise InputError("scene: slide_speed_mm_s, slide_length_mm, sample_rate_hz and "
                             "cushion_stiffness_n_per_mm must be positive")

    def _protocol(self, charge):
        boards = resolve_boards(self.boards, charge)
        rows = [(m, t, float(f), p) for m, t in boards for f in self.force_levels_n
                for p in range(self.passes_per_level)]
        labels = pd.DataFrame(rows, columns=["material", "texture", "force_level_n", "pass"])
        labels.insert(0, "board", labels["material"] + "/" + labels["texture"])
        return labels

    def _kinematics(self, force_n, start_phase):
        """Time axis, gap, force, horizontal position and sliding flag for every pass."""
        v = self.slide_speed_mm_s
        vz = v * np.sin(np.radians(self.base_angle_deg))
        vx = v * np.cos(np.radians(self.base_angle_deg))
        h0 = self.approach_height_mm
        squeeze = force_n[:, None] / self.cushion_stiffness_n_per_mm / vz   # s to compress the cushion
        t0 = self.idle_s
        t_touch = t0 + h0 / vz
        t_loaded = t_touch + squeeze
        t_unload = t_loaded + self.slide_length_mm / v
        t_free = t_unload + squeeze
        t_up = t_free + h0 / vz
        n_steps = int(np.ceil((t_up.max() + self.idle_s) * self.sample_rate_hz))
        t = np.arange(n_steps) / self.sample_rate_hz
        tt = t[None, :]
        gap = h0 * (np.clip((t_touch - tt) / (t_touch - t0), 0, 1) + np.clip((tt - t_free) / (t_up - t_free), 0, 1))
        load = np.clip((tt - t_touch) / squeeze, 0, 1) * np.clip((t_free - tt) / squeeze, 0, 1)
        position = (vx * np.clip(tt - t0, 0, t_loaded - t0) + v * np.clip(tt - t_loaded, 0, t_unload - t_loaded)
                    + vx * np.clip(tt - t_unload, 0, t_up - t_unload)) + start_phase[:, None]
        sliding = (tt >= t_loaded) & (tt <= t_unload)
        return t, gap, force_n[:, None] * load, position, sliding

    # -- channels ---------------------------------------------------------------------------
    def _triboelectric_na(self, state):
        """I = dQ/dt with Q = contact-separation charge + sliding (grating/texture) charge."""
        force, sigma = state["force_n"], state["sigma_uc_m2"][:, None] * 1e-12       # C/mm^2
        charge_share = sigma * (1.0 - np.exp(-force / self.charge_force_scale_n))
        # The surfaces keep the charge they took at full load while the gap opens and closes.
        held = sigma * (1.0 - np.exp(-force.max(axis=1, keepdims=True) / self.charge_force_scale_n))
        area = self.fingertip_width_mm * self.fingertip_length_mm
        gap = state["gap_mm"]
        q = held * area * gap / (self.dielectric_gap_mm + gap)
        profile, period = state["profile"], state["period_mm"]
        pattern = 0.5 * (1 + np.sin(2 * np.pi * state["position_mm"] / self.grating_period_mm))
        scale = np.full(len(force), self.flat_efficiency * self.grating_period_mm)
        for name in np.unique(profile[period > 0]):
            rows = profile == name
            pattern[rows] = ridge_profile(name, state["position_mm"][rows] / period[rows, None])
            scale[rows] = self.sliding_efficiency * period[rows]
        q = q + charge_share * self.fingertip_width_mm * scale[:, None] * pattern
        return np.gradient(q, 1.0 / self.sample_rate_hz, axis=1) * 1e9

    def _piezoresistive_v(self, force):
        return divider_voltage_v(force, self.fsr_actuation_n, self.fsr_open_ohm, supply_v=self.supply_v,
                                 divider_resistor_ohm=self.divider_resistor_ohm,
                                 fsr_resistance_1n_ohm=self.fsr_resistance_1n_ohm, fsr_exponent=self.fsr_exponent,
                                 fsr_saturation_n=self.fsr_saturation_n)

    # -- simulation -------------------------------------------------------------------------
    def generate(self) -> RecordingSet:
        self._check()
        charge = {**CHARGE_DENSITY_UC_M2, **(self.charge_density_uc_m2 or {})}
        effects = resolve_effects(self.name, self.effects, EFFECTS)
        labels = self._protocol(charge)
        textures = [parse_texture(t) for t in labels["texture"]]
        profile = np.array([p for p, _ in textures])
        period = np.array([q or 0.0 for _, q in textures])
        rng = random_generator_for(self.seed, "protocol")
        start_phase = rng.uniform(0, 1, size=len(labels)) * np.where(period > 0, period, self.grating_period_mm)
        t, gap, force, position, sliding = self._kinematics(labels["force_level_n"].to_numpy(), start_phase)
        state = {"time_s": t, "gap_mm": gap, "force_n": force, "position_mm": position, "sliding": sliding,
                 "profile": profile, "period_mm": period,
                 "sigma_uc_m2": labels["material"].map(charge).to_numpy(dtype=float)}
        for name, fn, params in effects:
            if name in SOURCE_EFFECTS:
                fn(state, random_generator_for(self.seed, name), **params)
        state["triboelectric_na"] = self._triboelectric_na(state)
        state["piezoresistive_v"] = self._piezoresistive_v(state["force_n"])
        for name, fn, params in effects:
            if name in READING_EFFECTS:
                fn(state, random_generator_for(self.seed, name), **params)
        if "relative_humidity_pct" in state:
            labels["relative_humidity_pct"] = state["relative_humidity_pct"]
        signals = np.stack([state[c] for c in CHANNELS], axis=1).astype(np.float32)
        description = {"source": "scene", "scene": self.name, "boards": self.boards,
                       "effects": [name for name, _, _ in effects], "n_recordings": len(labels)}
        return RecordingSet(signals, list(CHANNELS), labels, self.sample_rate_hz, description)

    def load(self) -> RecordingSet:
        return self.generate()

