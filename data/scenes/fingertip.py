"""Scene `fingertip`: a hybrid triboelectric + piezoresistive fingertip sliding over boards.

Sensor (seed 003, sec. 2.2): a 20 x 23 mm, 3 mm thick fingertip: a silicone cushion, an FSR402
piezoresistive film, interdigitated copper grating electrodes, and a Kapton (polyimide) skin that is
the triboelectric layer. A robot moves it along a trapezoidal track: down a 30 deg incline until it
touches the board and the finger loads to the force level, across the board, and back up at 30 deg.
Each pass is one recording of two channels at 250 Hz: `triboelectric_na` (short-circuit current)
and `piezoresistive_v` (the FSR amplifier's output, 0-3.3 V). Protocol: every board x force level
{1, 5, 10, 15, 20, 25} N x 15 passes, recorded board by board (the session order humidity drifts
over); each pass starts at a random place on the board.

Load path. The finger and the cushion are springs in series. The cushion is a thin silicone pad
bonded between the finger and the film stack: under compression its apparent modulus is
E_c = E (1 + 2 k S^2), S = loaded area / free (bulging) area = w l / (2 (w + l) h), k ~ 0.75
(Gent & Lindley, Proc. Inst. Mech. Eng. 173 (1959) 111; Gent, *Engineering with Rubber*, 3rd ed.
2012, ch. 8), so k_cushion = E_c w l / h: a 1.5 mm pad of 0.5 MPa silicone (estimates; the paper
gives 3 mm for all four layers) compresses about 8 um at 25 N. The compliance that sets how long
the load takes to build is the 3D-printed finger's and the platform's (`finger_stiffness_n_per_mm`,
an estimate). In shear the pad is soft, G w l / h with G = E/3 (incompressible), in series with the
finger's tangential compliance: that spring drives stick-slip (data/physics/stick_slip.py).

Triboelectric channel (Niu et al., Adv. Mater. 25 (2013) 6184; Niu & Wang, Nano Energy 14 (2015)
161): the current is the rate of change of the charge induced on the two comb electrodes,

    Q = eta_cs sigma a_held A x / (d0 + x)                  contact-separation (gap x)
      + eta sigma a(F) w period c(X / period)               sliding over ridges (c: ridge contact share)
      + (roughness effect) xi sigma A0 s(F) dG(X)           the board's waviness under the combs

with a(F) = A_real / A0 the real contact fraction of the skin on the board at nominal pressure F/A0
(Persson; data/physics/rough_contact.py): charge is transferred where the surfaces touch, so it
saturates with load at a rate set by each material's roughness and modulus. X is the skin's
position over the board (behind the drive during stick-slip). A uniform charge approaching a pair
of interleaved combs induces nearly the same charge on both: only the uneven coupling of the comb
ends gives a differential contact-separation signal (freestanding mode, Niu & Wang 2015), hence
eta_cs < 1 (an estimate). A flat board carries no carrier: a uniform surface has no structure for
the grating to modulate; its sliding signal comes from the board's roughness and from stick-slip:
the waviness of the board modulates the local pressure by a share xi (an estimate), the contact
share answers with Persson's slope s = p0 da/dp0 (data/physics/rough_contact.py), and the combs
read that charge pattern through their period selectivity, dG = the comb-weighted surface profile
(data/physics/comb_electrodes.py): a narrow band around v / grating period whose strength is the
share of the board's roughness spectrum near the grating's wavelength.

Piezoresistive channel: an Interlink FSR 400-series film through the paper's non-inverting
amplifier (data/physics/force_sensing_resistor.py).

Only listed effects run (data/scenes/fingertip_effects.py): source effects before the channels are
synthesised, reading effects after, each with its own random stream.
"""
import numpy as np
import pandas as pd
from scipy.special import erf

from common.errors import InputError
from data.physics.force_sensing_resistor import (
    AMPLIFIER_DEFAULTS,
    FILM_DEFAULTS,
    amplifier_voltage_v,
    check_readout,
)
from data.physics.rough_contact import (
    contact_modulus_pa,
    real_contact_fraction,
    rms_slope,
)
from data.recording_set import RecordingSet
from data.scenes.contract import random_generator_for, resolve_effects
from data.scenes.fingertip_boards import (
    material_table,
    parse_texture,
    resolve_boards,
    ridge_profile,
)
from data.scenes.fingertip_effects import EFFECTS, READING_EFFECTS, SOURCE_EFFECTS

CHANNELS = ["triboelectric_na", "piezoresistive_v"]
GENT_LINDLEY_K = 0.75    # bonded-block compression coefficient, 0.57-0.93 with hardness (Gent 2012, ch. 8)


class FingertipScene:
    name = "fingertip"

    def __init__(self, boards="combined18", force_levels_n=(1, 5, 10, 15, 20, 25), passes_per_level=15,
                 seed=0, effects=None, sample_rate_hz=250.0, slide_speed_mm_s=15.0, slide_length_mm=90.0,
                 base_angle_deg=30.0, approach_height_mm=2.0, idle_s=0.3, start_offset_mm=10.0,
                 cushion_modulus_mpa=0.5, cushion_thickness_mm=1.5, finger_stiffness_n_per_mm=10.0,
                 fingertip_width_mm=20.0, fingertip_length_mm=23.0, dielectric_gap_mm=0.5,
                 contact_separation_efficiency=0.3, sliding_efficiency=0.5, grating_period_mm=2.0,
                 skin_modulus_mpa=1.0, skin_poisson_ratio=0.5, roughness_cutoff_mm=0.02,
                 materials=None, charge_density_uc_m2=None,
                 fsr_actuation_n=0.2, fsr_resistance_1n_ohm=FILM_DEFAULTS["fsr_resistance_1n_ohm"],
                 fsr_exponent=FILM_DEFAULTS["fsr_exponent"], fsr_saturation_n=FILM_DEFAULTS["fsr_saturation_n"],
                 fsr_open_ohm=1.0e7, supply_v=AMPLIFIER_DEFAULTS["supply_v"],
                 reference_v=AMPLIFIER_DEFAULTS["reference_v"],
                 feedback_resistor_ohm=AMPLIFIER_DEFAULTS["feedback_resistor_ohm"],
                 series_resistor_ohm=AMPLIFIER_DEFAULTS["series_resistor_ohm"]):
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
        self.start_offset_mm = start_offset_mm
        self.cushion_modulus_mpa = cushion_modulus_mpa
        self.cushion_thickness_mm = cushion_thickness_mm
        self.finger_stiffness_n_per_mm = finger_stiffness_n_per_mm
        self.fingertip_width_mm = fingertip_width_mm
        self.fingertip_length_mm = fingertip_length_mm
        self.dielectric_gap_mm = dielectric_gap_mm
        self.contact_separation_efficiency = contact_separation_efficiency
        self.sliding_efficiency = sliding_efficiency
        self.grating_period_mm = grating_period_mm
        self.skin_modulus_mpa = skin_modulus_mpa
        self.skin_poisson_ratio = skin_poisson_ratio
        self.roughness_cutoff_mm = roughness_cutoff_mm
        self.materials = materials
        self.charge_density_uc_m2 = charge_density_uc_m2
        self.fsr_actuation_n = fsr_actuation_n
        self.fsr_resistance_1n_ohm = fsr_resistance_1n_ohm
        self.fsr_exponent = fsr_exponent
        self.fsr_saturation_n = fsr_saturation_n
        self.fsr_open_ohm = fsr_open_ohm
        self.supply_v = supply_v
        self.reference_v = reference_v
        self.feedback_resistor_ohm = feedback_resistor_ohm
        self.series_resistor_ohm = series_resistor_ohm

    # -- parameters -------------------------------------------------------------------------
    def _check(self):
        levels = np.asarray(self.force_levels_n, dtype=float)
        if levels.size == 0 or (levels <= 0).any():
            raise InputError(f"scene.force_levels_n must be positive newtons, got {list(self.force_levels_n)}")
        if not isinstance(self.passes_per_level, int) or self.passes_per_level < 1:
            raise InputError(f"scene.passes_per_level must be a positive integer, got {self.passes_per_level!r}")
        positive = ("slide_speed_mm_s", "slide_length_mm", "sample_rate_hz", "approach_height_mm",
                    "cushion_modulus_mpa", "cushion_thickness_mm", "finger_stiffness_n_per_mm", "fingertip_width_mm",
                    "fingertip_length_mm", "dielectric_gap_mm", "skin_modulus_mpa", "roughness_cutoff_mm",
                    "grating_period_mm")
        for key in positive:
            value = getattr(self, key)
            if not np.isfinite(value) or value <= 0:
                raise InputError(f"scene.{key} must be positive, got {value}")
        for key in ("contact_separation_efficiency", "sliding_efficiency"):
            if not 0 <= getattr(self, key) <= 1:
                raise InputError(f"scene.{key} must lie in [0, 1], got {getattr(self, key)}")
        if not 0 < self.base_angle_deg <= 90:
            raise InputError(f"scene.base_angle_deg must lie in (0, 90], got {self.base_angle_deg}")
        if self.start_offset_mm < 0 or self.idle_s < 0:
            raise InputError("scene: start_offset_mm and idle_s must be >= 0")
        check_readout(**self._readout())

    def _readout(self) -> dict:
        return {"supply_v": self.supply_v, "reference_v": self.reference_v,
                "feedback_resistor_ohm": self.feedback_resistor_ohm, "series_resistor_ohm": self.series_resistor_ohm,
                "fsr_resistance_1n_ohm": self.fsr_resistance_1n_ohm, "fsr_exponent": self.fsr_exponent,
                "fsr_saturation_n": self.fsr_saturation_n}

    def material_properties(self) -> dict:
        overrides = {name: dict(values) for name, values in (self.materials or {}).items()}
        for name, charge in (self.charge_density_uc_m2 or {}).items():
            overrides.setdefault(name, {})["charge_density_uc_m2"] = charge
        return material_table(overrides)

    @property
    def nominal_area_mm2(self) -> float:
        return self.fingertip_width_mm * self.fingertip_length_mm

    @property
    def cushion_stiffness_n_per_mm(self) -> float:
        """Bonded pad in compression: E (1 + 2 k S^2) w l / h (Gent & Lindley 1959)."""
        w, l, h = self.fingertip_width_mm, self.fingertip_length_mm, self.cushion_thickness_mm
        shape_factor = w * l / (2 * (w + l) * h)
        return self.cushion_modulus_mpa * (1 + 2 * GENT_LINDLEY_K * shape_factor ** 2) * w * l / h   # MPa mm = N/mm

    @property
    def normal_stiffness_n_per_mm(self) -> float:
        return 1.0 / (1.0 / self.cushion_stiffness_n_per_mm + 1.0 / self.finger_stiffness_n_per_mm)

    @property
    def cushion_shear_stiffness_n_per_mm(self) -> float:
        """G w l / h with G = E / 3 (incompressible silicone)."""
        return self.cushion_modulus_mpa / 3.0 * self.nominal_area_mm2 / self.cushion_thickness_mm

    def cushion_compression_mm(self, force_n):
        return np.asarray(force_n, dtype=np.float64) / self.cushion_stiffness_n_per_mm

    def real_contact_fraction(self, force_n, material: str) -> np.ndarray:
        """A_real / A0 of the skin on a board of `material` at total normal force `force_n`."""
        p = self.material_properties()[material]
        modulus, slope = self._contact_constants(p)
        return real_contact_fraction(np.asarray(force_n, dtype=np.float64) / self.nominal_area_mm2 * 1e6,
                                     modulus, slope)

    def _contact_constants(self, p):
        modulus = contact_modulus_pa((self.skin_modulus_mpa * 1e6, self.skin_poisson_ratio),
                                     (p["youngs_modulus_mpa"] * 1e6, p["poisson_ratio"]))
        slope = rms_slope(p["rms_height_um"], p["hurst_exponent"], p["roll_off_mm"], self.roughness_cutoff_mm)
        return modulus, slope

    # -- protocol ---------------------------------------------------------------------------
    def _protocol(self, materials):
        boards = resolve_boards(self.boards, materials)
        rows = [(m, t, float(f), p) for m, t in boards for f in self.force_levels_n
                for p in range(self.passes_per_level)]
        labels = pd.DataFrame(rows, columns=["material", "texture", "force_level_n", "pass"])
        labels.insert(0, "board", labels["material"] + "/" + labels["texture"])
        return labels

    def _kinematics(self, force_n, start_mm):
        """Time axis, gap, force, horizontal drive position, drive travel while sliding and the
        sliding flag for every pass."""
        v = self.slide_speed_mm_s
        vz = v * np.sin(np.radians(self.base_angle_deg))
        vx = v * np.cos(np.radians(self.base_angle_deg))
        h0 = self.approach_height_mm
        squeeze = force_n[:, None] / self.normal_stiffness_n_per_mm / vz   # s to load the finger and cushion
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
        travel = v * np.clip(tt - t_loaded, 0, t_unload - t_loaded)
        position = (vx * np.clip(tt - t0, 0, t_loaded - t0) + travel
                    + vx * np.clip(tt - t_unload, 0, t_up - t_unload)) + start_mm[:, None]
        sliding = (tt >= t_loaded) & (tt <= t_unload)
        return t, gap, force_n[:, None] * load, position, travel, sliding

    # -- channels ---------------------------------------------------------------------------
    def _contact_argument(self, state, force):
        """x = sqrt(2) p0 / (E* h'_rms): A_real / A0 = erf(x) (data/physics/rough_contact.py)."""
        scale = np.sqrt(2.0) * 1e6 / self.nominal_area_mm2 / (state["contact_modulus_pa"] * state["slope_rms"])
        return np.maximum(force, 0.0) * scale[:, None]

    def _triboelectric_na(self, state):
        """I = dQ/dt with Q = contact-separation + ridge + roughness charge (module docstring)."""
        sigma = state["sigma_uc_m2"][:, None] * 1e-12                                  # C/mm^2
        x = self._contact_argument(state, state["force_n"])
        fraction = erf(x)
        held = erf(self._contact_argument(state, state["force_n"].max(axis=1, keepdims=True)))
        gap = state["gap_mm"]
        q = (self.contact_separation_efficiency * self.nominal_area_mm2) * held * gap / (self.dielectric_gap_mm + gap)
        profile, period = state["profile"], state["period_mm"]
        ridged = period > 0
        if ridged.any():
            pattern = state.get("ridge_contact")         # force_ripple computed it at the same skin position
            if pattern is None:
                pattern = np.zeros_like(fraction)
                for name in np.unique(profile[ridged]):
                    rows = profile == name
                    pattern[rows] = ridge_profile(name, state["skin_position_mm"][rows] / period[rows, None])
            scale = np.where(ridged, self.sliding_efficiency * self.fingertip_width_mm * period, 0.0)
            q = q + scale[:, None] * fraction * pattern
        if "roughness_pattern" in state:
            sensitivity = (2.0 / np.sqrt(np.pi)) * x * np.exp(-x * x)      # p0 da/dp0
            q = q + state["roughness_scale_mm2"] * sensitivity * state["roughness_pattern"]
        return np.gradient(sigma * q, 1.0 / self.sample_rate_hz, axis=1) * 1e9

    def _piezoresistive_v(self, force):
        return amplifier_voltage_v(force, self.fsr_actuation_n, self.fsr_open_ohm, **self._readout())

    # -- simulation -------------------------------------------------------------------------
    def generate(self) -> RecordingSet:
        self._check()
        materials = self.material_properties()
        effects = resolve_effects(self.name, self.effects, EFFECTS)
        labels = self._protocol(materials)
        textures = [parse_texture(t) for t in labels["texture"]]
        profile = np.array([p for p, _ in textures])
        period = np.array([q or 0.0 for _, q in textures])
        rng = random_generator_for(self.seed, "protocol")
        start = rng.uniform(0, 1, size=len(labels)) * np.where(period > 0, period, self.start_offset_mm)
        t, gap, force, position, travel, sliding = self._kinematics(labels["force_level_n"].to_numpy(), start)
        constants = {m: self._contact_constants(materials[m]) for m in labels["material"].unique()}
        material = labels["material"].to_numpy()
        state = {"time_s": t, "gap_mm": gap, "force_n": force, "position_mm": position, "skin_position_mm": position,
                 "travel_mm": travel, "sliding": sliding, "profile": profile, "period_mm": period,
                 "labels": labels, "materials": materials,
                 "sigma_uc_m2": labels["material"].map(lambda m: materials[m]["charge_density_uc_m2"]).to_numpy(float),
                 "contact_modulus_pa": np.array([constants[m][0] for m in material]),
                 "slope_rms": np.array([constants[m][1] for m in material]),
                 "tangential_stiffness_n_per_mm": self.cushion_shear_stiffness_n_per_mm,
                 "fingertip_width_mm": self.fingertip_width_mm, "roughness_cutoff_mm": self.roughness_cutoff_mm,
                 "fingertip_length_mm": self.fingertip_length_mm, "grating_period_mm": self.grating_period_mm,
                 "nominal_area_mm2": self.nominal_area_mm2,
                 "sample_rate_hz": self.sample_rate_hz, "slide_speed_mm_s": self.slide_speed_mm_s}
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
