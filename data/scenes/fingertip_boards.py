"""The fingertip scene's boards: textures, materials and the seed paper's board sets.

Textures: `flat`, and ridges of three profiles (circular, triangular, trapezoidal) with
periods 4, 5, 6 and 7 mm: 13 in all. Circular and trapezoidal ridges fill half their period;
triangular ridges meet (V-grooves). The profile c(u) is the share of the fingertip's width a
ridge touches at phase u = x / period (0..1).

Materials and their triboelectric surface-charge density against the fingertip's Kapton
layer, in uC/m^2 (physics notes: 10-100+ uC/m^2). The ordering follows the triboelectric
series (materials that give electrons readily, far from polyimide, charge most); magnitudes
are set from the spread of the quantified series of Zou et al., Nat. Commun. 10, 1427 (2019),
which lists polymers only, so marble, carbon fibre and bakelite are estimates. Physics notes
mark these values "verify": they are scene parameters, override them in the YAML.
"""
import numpy as np

from data.errors import InputError

PERIODS_MM = (4, 5, 6, 7)
PROFILES = ("circular", "triangular", "trapezoidal")
TEXTURES = ("flat",) + tuple(f"{p}_{period}mm" for p in PROFILES for period in PERIODS_MM)

CHARGE_DENSITY_UC_M2 = {
    "glass": 85.0, "nylon": 80.0, "leather": 70.0, "silk": 65.0, "wood": 55.0, "paper": 50.0,
    "marble": 45.0, "acrylic": 40.0, "epoxy": 32.0, "resin": 28.0, "bakelite": 24.0, "carbon_fibre": 15.0,
}
MATERIALS10 = ("acrylic", "bakelite", "carbon_fibre", "epoxy", "marble", "leather", "nylon", "glass", "resin", "wood")

# The seed's board sets. textures13: every texture, printed in resin. materials10: every
# material, flat. combined18: silk and paper in five textures (flat and circular ridges of
# 4-7 mm: our reading of the paper) plus the first eight materials, flat.
BOARD_SETS = {
    "textures13": [("resin", t) for t in TEXTURES],
    "materials10": [(m, "flat") for m in MATERIALS10],
    "combined18": [(m, t) for m in ("silk", "paper") for t in ("flat",) + TEXTURES[1:5]]
                  + [(m, "flat") for m in MATERIALS10[:8]],
}


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


def resolve_boards(boards, charge_density_uc_m2: dict) -> list[tuple[str, str]]:
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
        if material not in charge_density_uc_m2:
            raise InputError(f"unknown material '{material}'; valid: {', '.join(sorted(charge_density_uc_m2))}")
        parse_texture(texture)
    return pairs
