"""Which physics lowers the taxels' shear sensitivity (fidelity row 4) while rows 1-3 hold.

    .venv/bin/python bench/taxel_shear_candidates.py          # 3 min at load average 14 on 2 shared cores

Each candidate is the default scene (configs/scene/taxels.yaml) with one thing changed, measured
with the fidelity probe (runs/fidelity/taxels.py, noise-free mechanics): the ratio and the shear
sensitivity max|gamma_x| / max|eps_z| at the paper's 180 um cover, W slope and A exponent over
150-1000 um. Deterministic: no seed enters. docs/taxels.md tabulates the output.
"""
import copy
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from runs.fidelity.observations import scene_params  # noqa: E402
from runs.fidelity.taxels import FIG2_THICKNESS_UM, TaxelsProbe  # noqa: E402
from runs.studies.taxel_receptive_field import THEORY, shear_sensitivity  # noqa: E402


def candidate(base: dict, membrane: dict | None = None, cover: dict | None = None, **params) -> dict:
    node = copy.deepcopy(base)
    node.update(params)
    node["effects"]["plate_averaging"].update(membrane or {})
    if cover is not None:
        node["effects"].pop("flat")
        node["effects"].update(cover)
    return node


def row(label: str, node: dict) -> None:
    m = TaxelsProbe(node, repeats=3).mechanics
    print(f"{label:58s} {m['ratio']:7.1f} {m['w_slope']:6.2f} {m['a_exponent']:6.2f} {m['shear_sensitivity']:6.3f}",
          flush=True)


def main() -> None:
    base = scene_params("taxels")
    print(f"theory: shear sensitivity {THEORY['shear_sensitivity']:.3f} at any depth (eq. 1)")
    print(f"{'candidate':58s} {'ratio':>7s} {'slope':>6s} {'exp':>6s} {'shear':>6s}")
    for tilt in (False, True):
        tag = "with tilt" if tilt else "no tilt"
        row(f"membrane 350 um, 4 x 4 points, {tag}", candidate(base, {"pressure_moment": tilt}))
        row(f"membrane 350 um, 12 x 12 points, {tag}", candidate(base, {"pressure_moment": tilt, "points_per_side": 12}))
        for side in (100.0, 200.0, 300.0, 380.0, 500.0):
            row(f"membrane {side:.0f} um, {tag}", candidate(base, {"pressure_moment": tilt, "side_um": side}))
        for nu in (0.49, 0.45):
            row(f"membrane 350 um, nu = {nu}, {tag}", candidate(base, {"pressure_moment": tilt}, poisson_ratio=nu))
        row(f"bonded layer, plate traction, 350 um, {tag}",
            candidate(base, {"pressure_moment": tilt}, cover={"finite_layer": {}}))
        probe = TaxelsProbe(candidate(base, {"pressure_moment": tilt}), repeats=3)
        for height in (10.0, 30.0, 60.0):
            strain = probe.scan(FIG2_THICKNESS_UM - height)[2]
            print(f"  sensing {height:.0f} um above the chip (depth {FIG2_THICKNESS_UM - height:.0f} um), {tag}: "
                  f"shear {shear_sensitivity(strain):.3f}")
    plate = TaxelsProbe(candidate(base, {"side_um": 100.0, "points_per_side": 3, "pressure_moment": False}), repeats=3).scan(FIG2_THICKNESS_UM)[2]
    membrane = TaxelsProbe(candidate(base, {"pressure_moment": False}), repeats=3).scan(FIG2_THICKNESS_UM)[2]
    print(f"  shear over the 100 um plate / eps_z over the 350 um membrane: "
          f"{np.abs(plate[:, 0]).max() / np.abs(membrane[:, 2]).max():.3f}")
    probe = TaxelsProbe(base, repeats=3)
    for z in (150.0, 180.0, 300.0, 400.0, 580.0, 1000.0):
        x, _, strain, centre = probe.scan(z)
        gamma = strain[x > centre, 0]
        reversed_lobe = max(gamma.max(), 0.0) / abs(gamma.min())
        print(f"  default at {z:.0f} um: shear {shear_sensitivity(strain):.3f}, reversed inner lobe of gamma_x "
              f"{reversed_lobe:.2f} of the main lobe")


if __name__ == "__main__":
    main()
