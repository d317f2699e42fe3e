"""The taxels paper's observations (*Effects of the elastic cover on tactile sensor arrays*,
../shared/notes/seed-observations.md seed 004 rows 1-6), measured on the taxels scene.

    .venv/bin/python bench/fidelity.py --scene taxels               # the table
    .venv/bin/python bench/fidelity.py --scene taxels --repeats 5   # fewer noise seeds

How each row is measured (the probe, `TaxelsProbe`, holds the composed scene config):
- rows 1-4 scan the paper's needle (10 mN) along a taxel row, the profile's features by eq. (3)-(4)
  (runs/studies/taxel_receptive_field.py: W between eps_z's zero crossings, A = |eps_z| at its
  peak, the ratio = |peak / tensile lobe|). "Mechanics" is the scene's noise-free strain at the
  taxel (its cover, needle, sensing area and the membrane's tilt: what the chain reads without
  noise); "read back" is eq. (2) applied to the bridge voltages through amplifier, noise and ADC,
  over `repeats` noise seeds (mean ± sd). Row 1 and 4 are at the paper's Fig. 2 cover (180 um); rows 2-3 fit W and A
  over the paper's Fig. 4 range (150-1000 um) on the mechanics (at 1000 um the tensile lobe is
  below the read-back noise, so a noisy W says nothing: that number is reported beside).
- rows 5-6 measure the surface structures on their own variants (taxels_bump, taxels_ridge,
  taxels_hair: the default cover and chain plus the structure), noise-free, as their figures do.
The tolerances are the issue's goals where it set one (ratio within 30 % of 19; W slope between
the measured 1.14 and the theory's 2.82) and otherwise the paper's direction.
"""
from functools import cached_property

import numpy as np

from common.spread import mean_and_sd
from data.scenes.taxels import TaxelsScene
from data.scenes.taxels_effects import READING_EFFECTS
from runs.fidelity.observations import Measured, observation, probe, scene_params
from runs.studies.taxel_receptive_field import (PAPER, THEORY, fit_laws, needle_profile, profile_metrics,
                                                shear_sensitivity)

FIG2_THICKNESS_UM = 180.0                                   # the paper's Fig. 2 cover
FIG4_THICKNESS_UM = (150.0, 200.0, 300.0, 400.0, 580.0, 700.0, 850.0, 1000.0)  # its Fig. 3-4 range
NEEDLE_FORCE_MN = 10.0
SCAN_POINTS = 1201
RATIO_TOLERANCE = 0.30


@probe("taxels")
class TaxelsProbe:
    """Needle scans of one taxels configuration (`params`: the composed scene config as a dict);
    `repeats` noise seeds for the read-back (seed 0, 1, ...)."""

    def __init__(self, params: dict, repeats: int = 20):
        self.params = {k: v for k, v in params.items() if k not in ("_target_", "_convert_")}
        self.repeats = max(int(repeats), 3)
        self.effects = dict(self.params.get("effects") or {})

    def scan(self, thickness_um: float, seed: int = 0, effects: dict | None = None):
        params = {**self.params, "seed": seed}
        return needle_profile(params, self.effects if effects is None else effects, thickness_um,
                              SCAN_POINTS, NEEDLE_FORCE_MN)

    @cached_property
    def mechanics(self) -> dict:
        """Noise-free features: the Fig. 2 profile at 180 um and the Fig. 4 laws over 150-1000 um."""
        x, _, exact, centre = self.scan(FIG2_THICKNESS_UM)
        fig2 = profile_metrics(x, exact[:, 2], centre)
        widths, amplitudes = [], []
        for z in FIG4_THICKNESS_UM:
            xz, _, exact_z, centre_z = self.scan(z)
            m = profile_metrics(xz, exact_z[:, 2], centre_z)
            widths.append(m["width_mm"])
            amplitudes.append(m["amplitude"])
        return {"ratio": fig2["ratio"], "shear_sensitivity": shear_sensitivity(exact),
                **fit_laws(FIG4_THICKNESS_UM, widths, amplitudes)}

    @cached_property
    def read_back(self) -> dict:
        """The Fig. 2 ratio and shear sensitivity through the whole chain, per noise seed."""
        ratios, shears = [], []
        for seed in range(self.repeats):
            x, strain, _, centre = self.scan(FIG2_THICKNESS_UM, seed)
            ratios.append(profile_metrics(x, strain[:, 2], centre)["ratio"])
            shears.append(shear_sensitivity(strain))
        return {"ratio": mean_and_sd(ratios), "shear_sensitivity": mean_and_sd(shears)}

    def variant(self, config: str) -> dict:
        """The composed config of a surface-structure variant (configs/scene/<config>.yaml)."""
        params = scene_params(config)
        return {k: v for k, v in params.items() if k not in ("_target_", "_convert_")}


def _scene(params: dict, **overrides):
    """The scene without its reading chain: the structure rows read the noise-free strain columns."""
    node = {**params, **overrides}
    node["effects"] = {k: v for k, v in (node.get("effects") or {}).items() if k not in READING_EFFECTS}
    return TaxelsScene(**node)


@observation("taxels", "1", "Lateral inhibition: |ε_z,max / ε_z,min| at 180 µm, measured ≈ 19 against the "
             "half-space's 56", "≈ 19 (theory 5^{5/2} = 55.9)")
def lateral_inhibition(probe: TaxelsProbe) -> Measured:
    mechanics = probe.mechanics["ratio"]
    mean, sd = probe.read_back["ratio"]
    low, high = (1 - RATIO_TOLERANCE) * PAPER["ratio"], (1 + RATIO_TOLERANCE) * PAPER["ratio"]
    holds = bool(low <= mechanics <= high and low <= mean <= high)
    return Measured(f"{mechanics:.1f} (mechanics); {mean:.1f} ± {sd:.1f} read back through the chain "
                    f"({probe.repeats} noise seeds)", holds, f"{low:.1f}-{high:.1f} (± 30 % of 19)",
                    {"mechanics": mechanics, "read_back": [mean, sd]})


@observation("taxels", "2", "Receptive-field width W grows linearly with cover thickness, slope 1.14 "
             "(theory W = 2√2·z, slope 2.82)", "slope 1.14 (theory 2.83)")
def width_slope(probe: TaxelsProbe) -> Measured:
    slope = probe.mechanics["w_slope"]
    holds = bool(PAPER["w_slope"] <= slope < THEORY["w_slope"])
    return Measured(f"slope {slope:.2f} over 150-1000 µm (mechanics)", holds,
                    "between the measured 1.14 and the theory's 2.83", {"w_slope": slope})


@observation("taxels", "3", "Amplitude falls as z^−1.45 (theory z^−2)", "exponent −1.45 (theory −2)")
def amplitude_exponent(probe: TaxelsProbe) -> Measured:
    exponent = probe.mechanics["a_exponent"]
    holds = bool(abs(exponent - PAPER["a_exponent"]) <= 0.25)
    return Measured(f"exponent {exponent:.2f} over 150-1000 µm (mechanics)", holds, "−1.45 ± 0.25",
                    {"a_exponent": exponent})


@observation("taxels", "4", "Shear sensitivity below the theory's (max |γ_x| / max |ε_z| during a normal "
             "needle scan); a rigid rod on the membrane (a hair) raises it", "below 0.429; hair above")
def shear_below_theory(probe: TaxelsProbe) -> Measured:
    mechanics = probe.mechanics["shear_sensitivity"]
    mean, sd = probe.read_back["shear_sensitivity"]
    hair = hair_shear_ratio(probe)
    below = mechanics < THEORY["shear_sensitivity"] and mean < THEORY["shear_sensitivity"]
    raised = hair["hair"] > hair["flat"]
    return Measured(f"{mechanics:.3f} (mechanics), {mean:.3f} ± {sd:.3f} read back; "
                    f"moving load peak |γ_x|/|ε_z|: hair {hair['hair']:.2f} vs flat {hair['flat']:.2f}",
                    bool(below and raised), f"< {THEORY['shear_sensitivity']:.3f}; hair > flat",
                    {"mechanics": mechanics, "read_back": [mean, sd], **hair})


def _moving_peak(params, direction_deg, component, **overrides):
    frame = _scene(params, protocol="moving_loads", n_samples=601, directions_deg=[direction_deg],
                   **overrides).generate().frame
    return float(np.abs(frame[component]).max())


def hair_shear_ratio(probe: TaxelsProbe) -> dict:
    """Fig. 6: peak |gamma_x| / peak |eps_z| of a 10 mN load with mu = 0.3 moved along x over taxel
    0, on taxels_hair and on the same cover without the rod."""
    hair = probe.variant("taxels_hair")
    plain = {**hair, "effects": {k: v for k, v in hair["effects"].items() if k != "hair"}}
    return {name: _moving_peak(p, 0.0, "gamma_x_t0") / _moving_peak(p, 0.0, "eps_z_t0")
            for name, p in (("hair", hair), ("flat", plain))}


@observation("taxels", "5", "A spherical bump above a taxel raises its lateral (tangential) sensitivity "
             "(Fig. 9)", "larger shear loops (no number)")
def bump_raises_lateral_sensitivity(probe: TaxelsProbe) -> Measured:
    bump = probe.variant("taxels_bump")
    probe_um = 3000.0       # a fingertip-sized probe resting on the bumps (Fig. 9 used a finger)
    with_bumps = {**bump, "effects": {**bump["effects"], "bump": {**bump["effects"]["bump"],
                                                                 "probe_diameter_um": probe_um}}}
    flat = {**bump, "effects": {**{k: v for k, v in bump["effects"].items() if k != "bump"},
                                "needle": {"diameter_um": probe_um, "rings": 6, "points_per_ring": 16}}}
    gains = []
    for seed in range(3):
        x, y = np.random.default_rng(seed).uniform(-0.3, 0.3, (2, 200))
        responses = [np.abs(_scene(p).simulate(x, y, 0.0, 1.0, 0.0).frame.gamma_x_t0).mean()
                     for p in (with_bumps, flat)]
        gains.append(responses[0] / responses[1])
    mean, sd = mean_and_sd(gains)
    return Measured(f"mean |γ_x| per unit shear under a 3 mm probe, bumps / flat: {mean:.2f} ± {sd:.2f} "
                    "(3 sets of 200 probe positions)", bool(min(gains) > 1.0), "> 1 in every set (the paper's direction)",
                    {"gain": [mean, sd]})


@observation("taxels", "6", "A ridge perpendicular to the motion integrates the load and codes its shear "
             "direction; parallel to the motion it behaves like the flat cover: direction selective (Fig. 10)",
             "qualitative (Fig. 10c-d)")
def ridge_direction_selective(probe: TaxelsProbe) -> Measured:
    """Across: peak shear of a 10 mN load (mu = 0.3) moved across the ridge over peak shear moved
    along it. Along: the correlation of taxel 0's eps_z profile under a load moved along the ridge
    with the flat cover's (the same shape: "the complicated strain distribution")."""
    ridge = probe.variant("taxels_ridge")
    flat = {**ridge, "effects": {k: v for k, v in ridge["effects"].items() if k != "ridge"}}
    selectivity = _moving_peak(ridge, 90.0, "gamma_y_t0") / _moving_peak(ridge, 0.0, "gamma_x_t0")
    isotropy = _moving_peak(flat, 90.0, "gamma_y_t0") / _moving_peak(flat, 0.0, "gamma_x_t0")
    along = [_scene(p, protocol="moving_loads", n_samples=601, directions_deg=[0.0]).generate().frame.eps_z_t0
             for p in (ridge, flat)]
    shape = float(np.corrcoef(along[0], along[1])[0, 1])
    holds = bool(selectivity > 1.0 and abs(isotropy - 1.0) < 1e-6 and shape > 0.9)
    return Measured(f"peak shear moved across / along the ridge {selectivity:.2f} (flat cover {isotropy:.3f}); "
                    f"ε_z along the ridge vs flat: correlation {shape:.4f}", holds,
                    "across/along > 1, flat 1; along-ridge shape correlation > 0.9",
                    {"selectivity": selectivity, "isotropy": isotropy, "shape_correlation": shape})
