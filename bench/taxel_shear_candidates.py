"""Which physics lowers the taxels' shear sensitivity (fidelity row 4) while rows 1-3 hold.

    .venv/bin/python bench/taxel_shear_candidates.py          # 3 min at load average 14 on 2 shared cores

Each candidate is the default scene (configs/scene/taxels.yaml) with one thing changed, measured
with the fidelity probe (runs/fidelity/taxels.py, noise-free mechanics): the ratio and the shear
sensitivity max|gamma_x| / max|eps_z| at the paper's 180 um cover, W slope and A exponent over
150-1000 um. Deterministic: no seed enters. docs/taxels.md tabulates the output, appended to
results/taxel_shear_candidates.jsonl (common/result_records.py).
"""
import argparse
import copy
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from common.result_records import recording  # noqa: E402
from runs.fidelity.observations import scene_params  # noqa: E402
from runs.fidelity.taxels import FIG2_THICKNESS_UM, TaxelsProbe  # noqa: E402
from runs.studies.taxel_receptive_field import THEORY, shear_sensitivity  # noqa: E402

# What each number measures: the probe and its laws, the scene's physics and its default config.
MEASURED_CODE = ["runs/fidelity/taxels.py", "runs/studies/taxel_receptive_field.py", "data/scenes/taxels.py",
                 "data/scenes/taxels_effects.py", "data/physics/", "configs/scene/taxels.yaml"]


def candidate(base: dict, membrane: dict | None = None, cover: dict | None = None, **params) -> dict:
    node = copy.deepcopy(base)
    node.update(params)
    node["effects"]["plate_averaging"].update(membrane or {})
    if cover is not None:
        node["effects"].pop("flat")
        node["effects"].update(cover)
    return node


def row(label: str, node: dict, tilt: bool) -> dict:
    m = TaxelsProbe(node, repeats=3).mechanics
    print(f"{label:58s} {m['ratio']:7.1f} {m['w_slope']:6.2f} {m['a_exponent']:6.2f} {m['shear_sensitivity']:6.3f}",
          flush=True)
    return {"candidate": label, "tilt": tilt, **m}


def candidates(base: dict) -> tuple[list[dict], list[dict]]:
    """The candidates' table and, per tilt, the shear sensed at heights inside the cover."""
    rows, heights = [], []
    for tilt in (False, True):
        tag = "with tilt" if tilt else "no tilt"
        rows.append(row(f"membrane 350 um, 4 x 4 points, {tag}", candidate(base, {"pressure_moment": tilt}), tilt))
        rows.append(row(f"membrane 350 um, 12 x 12 points, {tag}",
                        candidate(base, {"pressure_moment": tilt, "points_per_side": 12}), tilt))
        for side in (100.0, 200.0, 300.0, 380.0, 500.0):
            node = candidate(base, {"pressure_moment": tilt, "side_um": side})
            rows.append(row(f"membrane {side:.0f} um, {tag}", node, tilt))
        for nu in (0.49, 0.45):
            rows.append(row(f"membrane 350 um, nu = {nu}, {tag}",
                            candidate(base, {"pressure_moment": tilt}, poisson_ratio=nu), tilt))
        rows.append(row(f"bonded layer, plate traction, 350 um, {tag}",
                        candidate(base, {"pressure_moment": tilt}, cover={"finite_layer": {}}), tilt))
        probe = TaxelsProbe(candidate(base, {"pressure_moment": tilt}), repeats=3)
        for height in (10.0, 30.0, 60.0):
            shear = shear_sensitivity(probe.scan(FIG2_THICKNESS_UM - height)[2])
            print(f"  sensing {height:.0f} um above the chip (depth {FIG2_THICKNESS_UM - height:.0f} um), {tag}: "
                  f"shear {shear:.3f}")
            heights.append({"height_um": height, "depth_um": FIG2_THICKNESS_UM - height, "tilt": tilt,
                            "shear_sensitivity": shear})
    return rows, heights


def plate_over_membrane(base: dict) -> float:
    plate = TaxelsProbe(candidate(base, {"side_um": 100.0, "points_per_side": 3, "pressure_moment": False}), repeats=3).scan(FIG2_THICKNESS_UM)[2]
    membrane = TaxelsProbe(candidate(base, {"pressure_moment": False}), repeats=3).scan(FIG2_THICKNESS_UM)[2]
    ratio = np.abs(plate[:, 0]).max() / np.abs(membrane[:, 2]).max()
    print(f"  shear over the 100 um plate / eps_z over the 350 um membrane: {ratio:.3f}")
    return ratio


def default_by_depth(base: dict) -> list[dict]:
    """The default's shear sensitivity and gamma_x's reversed inner lobe at each cover thickness."""
    probe, rows = TaxelsProbe(base, repeats=3), []
    for z in (150.0, 180.0, 300.0, 400.0, 580.0, 1000.0):
        x, _, strain, centre = probe.scan(z)
        gamma = strain[x > centre, 0]
        reversed_lobe = max(gamma.max(), 0.0) / abs(gamma.min())
        print(f"  default at {z:.0f} um: shear {shear_sensitivity(strain):.3f}, reversed inner lobe of gamma_x "
              f"{reversed_lobe:.2f} of the main lobe")
        rows.append({"thickness_um": z, "shear_sensitivity": shear_sensitivity(strain), "reversed_lobe": reversed_lobe})
    return rows


def main() -> None:
    argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter).parse_args()
    base = scene_params("taxels")
    print(f"theory: shear sensitivity {THEORY['shear_sensitivity']:.3f} at any depth (eq. 1)")
    print(f"{'candidate':58s} {'ratio':>7s} {'slope':>6s} {'exp':>6s} {'shear':>6s}")
    with recording("taxel_shear_candidates", MEASURED_CODE) as record:  # deterministic: no seeds
        rows, heights = candidates(base)
        record.add("candidates", {"theory_shear_sensitivity": THEORY["shear_sensitivity"],
                                  "fig2_thickness_um": FIG2_THICKNESS_UM, "rows": rows})
        record.add("sensing_height", {"rows": heights})
        record.add("plate_over_membrane", {"plate_side_um": 100.0, "ratio": plate_over_membrane(base),
                                           "membrane_side_um": base["effects"]["plate_averaging"]["side_um"]})
        record.add("default_by_depth", {"rows": default_by_depth(base)})


if __name__ == "__main__":
    main()
