"""The fingertip scene's boards: textures, materials (with their physical properties) and the
seed paper's board sets.

Textures: `flat`, and ridges of three profiles (circular, triangular, trapezoidal) with
periods 4, 5, 6 and 7 mm: 13 in all. Circular and trapezoidal ridges fill half their period;
triangular ridges meet (V-grooves). The profile c(u) is the share of the fingertip's width a
ridge touches at phase u = x / period (0..1).

Materials (MATERIALS), each against the fingertip's Kapton (polyimide) skin:
- `charge_density_uc_m2`: triboelectric surface-charge density at full contact (physics notes:
  10-100+ uC/m^2). Ordering from the triboelectric series (materials that give electrons
  readily, far from polyimide, charge most); magnitudes in the spread of the quantified series of
  Zou et al., Nat. Commun. 10 (2019) 1427 (measured against liquid mercury, i.e. at full contact),
  which lists polymers only: marble, carbon fibre, bakelite, leather, silk, paper and wood are
  estimates. Physics notes mark all of these "verify". Issue 42 asked to size them from Zou et
  al.'s table: blocked, the table could not be read here (docs/fingertip.md).
- `static_friction`, `kinetic_friction` against polyimide film. Anchor: Kapton HN on itself,
  static 0.63, kinetic 0.48 (DuPont, *Kapton HN technical data sheet*, summary of properties);
  polymer-polymer and polymer-glass/stone pairs lie at 0.2-0.7 (Rabinowicz, *Friction and Wear of
  Materials*, 1995, ch. 4; Bhushan, *Introduction to Tribology*, 2013, ch. 5). The individual
  values are estimates within those ranges (nylon and carbon-fibre/epoxy laminates low, leather high).
- `rms_height_um`, `hurst_exponent`, `roll_off_mm`: the self-affine roughness of
  data/physics/rough_contact.py. Hurst exponents 0.6-0.9 (Persson, Tribol. Lett. 54 (2014) 99:
  most surfaces have H ~ 0.7-0.9). rms heights are estimates from typical finishes: float glass
  (nm), cast acrylic sheet (tens of nm), polished stone and moulded/laminated plastics (0.3-0.8 um),
  stereolithography prints (1-2 um), sanded wood, copy paper, leather and woven silk (3-15 um).
- `youngs_modulus_mpa`, `poisson_ratio`: the board's modulus under contact (Ashby, *Materials
  Selection in Mechanical Design*, 4th ed. 2011, property charts): soda-lime glass 70 GPa, PMMA
  3 GPa, nylon 6/6 2.8 GPa, marble 50 GPa, phenolic laminate 7 GPa, glass-epoxy laminate 20 GPa,
  carbon-fibre laminate 10 GPa through the thickness, photopolymer resin 2.5 GPa, wood across the
  grain 1 GPa, leather 50 MPa, paper through its thickness 30 MPa, woven silk in transverse
  compression 2 MPa (the last five estimates).
- `charge_decay_s`: the time constant with which a board's tribocharge bleeds away between passes
  (surface conduction through adsorbed water, faster on hydrophilic glass, paper, wood, nylon;
  carbon fibres conduct: estimates, of the order reported for polymers in air, seconds to hours;
  e.g. Lowell & Rose-Innes, Adv. Phys. 29 (1980) 947, sec. 5).
"""
import numpy as np

from common.errors import InputError

PERIODS_MM = (4, 5, 6, 7)
PROFILES = ("circular", "triangular", "trapezoidal")
TEXTURES = ("flat",) + tuple(f"{p}_{period}mm" for p in PROFILES for period in PERIODS_MM)

PROPERTIES = ("charge_density_uc_m2", "static_friction", "kinetic_friction", "rms_height_um", "hurst_exponent",
              "roll_off_mm", "youngs_modulus_mpa", "poisson_ratio", "charge_decay_s")
_TABLE = {  # charge, mu_s, mu_k, Rq um, H, roll-off mm, E MPa, nu, decay s
    "glass":        (85.0, 0.50, 0.40, 0.005, 0.90, 5.0, 70000.0, 0.22, 60.0),
    "nylon":        (80.0, 0.35, 0.30, 0.4, 0.80, 1.0, 2800.0, 0.39, 120.0),
    "leather":      (70.0, 0.65, 0.45, 10.0, 0.70, 1.0, 50.0, 0.40, 120.0),
    "silk":         (65.0, 0.30, 0.24, 15.0, 0.60, 0.5, 2.0, 0.30, 300.0),
    "wood":         (55.0, 0.50, 0.35, 6.0, 0.70, 1.0, 1000.0, 0.35, 120.0),
    "paper":        (50.0, 0.45, 0.33, 3.0, 0.70, 0.5, 30.0, 0.30, 60.0),
    "marble":       (45.0, 0.45, 0.38, 0.3, 0.80, 2.0, 50000.0, 0.25, 300.0),
    "acrylic":      (40.0, 0.55, 0.45, 0.05, 0.85, 3.0, 3000.0, 0.37, 1800.0),
    "epoxy":        (32.0, 0.45, 0.36, 0.4, 0.80, 2.0, 20000.0, 0.30, 1800.0),
    "resin":        (28.0, 0.55, 0.42, 1.5, 0.80, 1.0, 2500.0, 0.38, 900.0),
    "bakelite":     (24.0, 0.40, 0.32, 0.3, 0.80, 2.0, 7000.0, 0.35, 900.0),
    "carbon_fibre": (15.0, 0.30, 0.25, 0.8, 0.75, 3.0, 10000.0, 0.30, 5.0),
}
MATERIALS = {name: dict(zip(PROPERTIES, values)) for name, values in _TABLE.items()}
CHARGE_DENSITY_UC_M2 = {name: p["charge_density_uc_m2"] for name, p in MATERIALS.items()}
MATERIALS10 = ("acrylic", "bakelite", "carbon_fibre", "epoxy", "marble", "leather", "nylon", "glass", "resin", "wood")

# The seed's board sets (paper sec. 4.2). textures13: every texture, printed in resin.
# materials10: every material, flat. combined18 (sec. 4.2.3): silk and paper each in Flat, Cir4,
# Cir6, Tri4, Tri6, plus acrylic, bakelite, marble, leather, nylon, glass, resin and wood, flat.
COMBINED_TEXTURES = ("flat", "circular_4mm", "circular_6mm", "triangular_4mm", "triangular_6mm")
BOARD_SETS = {
    "textures13": [("resin", t) for t in TEXTURES],
    "materials10": [(m, "flat") for m in MATERIALS10],
    "combined18": [(m, t) for m in ("silk", "paper") for t in COMBINED_TEXTURES]
                  + [(m, "flat") for m in ("acrylic", "bakelite", "marble", "leather", "nylon", "glass", "resin",
                                           "wood")],
}


def material_table(overrides: dict | None = None) -> dict:
    """MATERIALS with per-material overrides ({material: {property: value}}), checked: an unknown
    material or property, or an impossible value, is a one-line InputError."""
    table = {name: dict(p) for name, p in MATERIALS.items()}
    for name, values in (overrides or {}).items():
        if not isinstance(values, dict):
            raise InputError(f"scene.materials.{name} must map properties to values, got {values!r}")
        unknown = sorted(set(values) - set(PROPERTIES))
        if unknown:
            raise InputError(f"scene.materials.{name}: unknown property '{unknown[0]}'; valid: {', '.join(PROPERTIES)}")
        if name not in table:
            missing = sorted(set(PROPERTIES) - set(values))
            if missing:
                raise InputError(f"scene.materials.{name}: a new material needs every property; missing {', '.join(missing)}")
            table[name] = {}
        table[name].update({k: float(v) for k, v in values.items()})
    for name, p in table.items():
        check_material(name, p)
    return table


def check_material(name: str, p: dict) -> None:
    for key in ("charge_density_uc_m2", "rms_height_um", "roll_off_mm", "youngs_modulus_mpa", "charge_decay_s"):
        if not np.isfinite(p[key]) or p[key] <= 0:
            raise InputError(f"material '{name}': {key} must be positive, got {p[key]}")
    if p["kinetic_friction"] < 0 or p["static_friction"] < p["kinetic_friction"]:
        raise InputError(f"material '{name}': friction must satisfy 0 <= kinetic <= static, got static "
                         f"{p['static_friction']}, kinetic {p['kinetic_friction']}")
    if not 0 < p["hurst_exponent"] < 1:
        raise InputError(f"material '{name}': hurst_exponent must lie in (0, 1), got {p['hurst_exponent']}")
    if not -1 < p["poisson_ratio"] <= 0.5:
        raise InputError(f"material '{name}': poisson_ratio must lie in (-1, 0.5], got {p['poisson_ratio']}")


def parse_texture(texture: str) -> tuple[str, float | None]:
    """'triangular_5mm' -> ('triangular', 5.0); 'flat' -> ('flat', None)."""
    if texture == "flat":
        return "flat", None
    profile, _, period = texture.rpartition("_")
    if profile not in PROFILES or not period.endswith("mm"):
        raise InputError(f"unknown texture '{texture}'; valid: {', '.join(TEXTURES)}")
    return profile, float(period[:-2])


def ridge_profile(profile: str, phase) -> np.ndarray:
    """Contact share c(u) of one ridge period at phase u in [0, 1), the ridge centred on u = 0.5."""
    offset = np.abs(np.mod(phase, 1.0) - 0.5)
    if profile == "circular":      # a rounded ridge: a quarter-cosine on each flank
        return np.where(offset < 0.25, np.cos(2.0 * np.pi * offset), 0.0)
    if profile == "triangular":    # V-grooves: ridges meet, the profile is a triangle wave
        return 1.0 - offset / 0.5
    if profile == "trapezoidal":   # flat top over 40 % of the ridge, linear flanks
        return np.clip((0.25 - offset) / 0.15, 0.0, 1.0)
    raise InputError(f"unknown ridge profile '{profile}'; valid: {', '.join(PROFILES)}")


def resolve_boards(boards, materials: dict) -> list[tuple[str, str]]:
    """A board-set name or a list of 'material/texture' strings -> [(material, texture)]."""
    if isinstance(boards, str):
        if boards not in BOARD_SETS:
            raise InputError(f"unknown board set '{boards}'; valid: {', '.join(BOARD_SETS)} "
                             "or a list of 'material/texture'")
        pairs = BOARD_SETS[boards]
    else:
        pairs = []
        for entry in boards:
            material, _, texture = str(entry).partition("/")
            pairs.append((material, texture or "flat"))
    for material, texture in pairs:
        if material not in materials:
            raise InputError(f"unknown material '{material}'; valid: {', '.join(sorted(materials))}")
        parse_texture(texture)
    return pairs
