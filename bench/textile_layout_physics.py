"""Which physics makes the ERT skin's boundary electrodes worse than internal ones (seed 002, issue 28
item 4): the paper's single-point protocol (runs/fidelity/ert.py `single_point_protocol`) on both
layouts for each physics variant, over seeds; optionally the two-point test. One JSON line per
variant and layout to --out, a table on stdout; one record per variant, layout and test appended
to results/textile_layout_physics.jsonl.

    OMP_NUM_THREADS=1 .venv/bin/python bench/textile_layout_physics.py --out /tmp/layout.jsonl
    OMP_NUM_THREADS=1 .venv/bin/python bench/textile_layout_physics.py --variants today local_contact --two-point
"""
import argparse
import json
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from common.result_records import recording  # noqa: E402
from runs.fidelity.ert import LAYOUTS, layout_variant, single_point_protocol, two_point_protocol  # noqa: E402

# What a variant's scores measure: the scene, its effects and its sheet solver, the paper's
# protocols (and the config they start from), and the reconstructions they fit.
MEASURED_CODE = ["data/scenes/ert.py", "data/scenes/ert_effects.py", "data/physics/sheet_conduction.py",
                 "data/physics/press_update.py", "data/physics/textile_contact.py", "runs/fidelity/ert.py",
                 "runs/fidelity/observations.py", "runs/studies/ert_tests.py", "models/ert/",
                 "data/ert/", "configs/scene/"]

PHYSICAL = {"local_contact": {}, "textile_contact": {}, "viscoelastic_hysteresis": {}}
RESTORING = {"baseline_drift": {"fraction_per_50_presses": 0.0057, "restoring_presses": 10.0}}   # ert_indentation_*
PER_POINT = {"recording_presses": 6}          # the unloaded frame before each point's six-force ramp
# name: (effects added, effects removed, scene overrides[, reconstruction settings])
VARIANTS = {
    "today": ({}, (), {}),
    "local_contact": ({"local_contact": {}}, (), {}),
    "contact_impedance_1k_5pct": ({"electrode_contact_impedance": {}}, (), {}),
    "contact_impedance_5k_20pct": ({"electrode_contact_impedance": {"resistance_ohm": 5000.0,
                                                                    "drift_fraction_per_50_presses": 0.2}}, (), {}),
    "anisotropy_2": ({"fabric_anisotropy": {"ratio": 2.0}}, (), {}),
    "electrode_width_10mm": ({}, (), {"electrode_width_mm": 10.0}),
    "noise_x5": ({"adc_noise": {"noise_v": 1.0e-3, "bits": 24, "full_scale_v": 10.0}}, (), {}),
    "textile_physics": (PHYSICAL, ("contact_resistance", "hysteresis"), {}),
    "inhomogeneous_30pct": ({"specimen_variation": {"base_resistance_spread": 0.3, "sensitivity_spread": 0.33}}, (), {}),
    "electrode_error_5mm": ({"electrode_position_error": {"sd_mm": 5.0}}, (), {}),
    "noise_x2": ({"adc_noise": {"noise_v": 4.0e-4, "bits": 24, "full_scale_v": 10.0}}, (), {}),
    "physical_all": ({**PHYSICAL, "electrode_contact_impedance": {}}, ("contact_resistance", "hysteresis"), {}),
    "same_alpha_1e-3": ({}, (), {}, {"alpha_relative": [1.0e-3]}),
    "same_alpha_1e-2": ({}, (), {}, {"alpha_relative": [1.0e-2]}),
    "anisotropy_2_physical": ({**PHYSICAL, "electrode_contact_impedance": {}, "fabric_anisotropy": {"ratio": 2.0}},
                              ("contact_resistance", "hysteresis"), {}),
    "baseline_per_point": ({}, (), PER_POINT),
    "physical_per_point": ({**PHYSICAL, "electrode_contact_impedance": {}}, ("contact_resistance", "hysteresis"),
                           PER_POINT),
    "drift_restoring_10": (RESTORING, (), {}),
    "drift_restoring_50": ({"baseline_drift": {"fraction_per_50_presses": 0.0057, "restoring_presses": 50.0}}, (), {}),
    "restoring_50_per_point": ({"baseline_drift": {"fraction_per_50_presses": 0.0057, "restoring_presses": 50.0}}, (),
                               PER_POINT),
    "restoring_per_point": (RESTORING, (), PER_POINT),
    "restoring_per_point_anisotropy_2": ({**RESTORING, "fabric_anisotropy": {"ratio": 2.0}}, (), PER_POINT),
    "restoring_per_point_electrode_error_5mm": ({**RESTORING, "electrode_position_error": {"sd_mm": 5.0}}, (), PER_POINT),
    "physical_restoring_per_point": ({**PHYSICAL, **RESTORING, "electrode_contact_impedance": {"restoring_presses": 10.0}},
                                     ("contact_resistance", "hysteresis"), PER_POINT),
    "restoring_per_point_noise_x5": ({**RESTORING, "adc_noise": {"noise_v": 1.0e-3, "bits": 24, "full_scale_v": 10.0}}, (),
                                     PER_POINT),
    "restoring_per_point_same_alpha_1e-3": (RESTORING, (), PER_POINT, {"alpha_relative": [1.0e-3]}),
    "two_point_4n": ({}, (), {"two_point_force_n": 4.0}),
    "ideal": ({}, ("specimen_variation", "electrode_position_error", "foam_spread", "hysteresis", "baseline_drift"), {}),
}


def reconstruction_settings(name: str, kind: str | None) -> dict:
    """What the variant and --kind pass to the single-point protocol's reconstruction."""
    _, _, _, *reconstruction = VARIANTS[name]
    return {**(reconstruction[0] if reconstruction else {}), **({"kind": kind} if kind else {})}


def measure(name: str, layout: str, args) -> dict:
    """One variant on one layout: the single-point and/or two-point test over the seeds."""
    add, remove, overrides, *_ = VARIANTS[name]
    cfg = layout_variant(layout, add, remove, **overrides)
    start, load = time.time(), os.getloadavg()[0]
    result = {"variant": name, "layout": layout, "seeds": args.seeds, "kind": args.kind or "tikhonov"}
    settings = reconstruction_settings(name, args.kind)
    if not args.two_point_only:
        result["single_point"] = single_point_protocol(cfg, tuple(args.seeds), reconstruction=settings or None)
    if args.two_point or args.two_point_only:
        result["two_point"] = two_point_protocol(cfg, tuple(args.seeds), placement_sd_mm=args.placement_sd_mm)
        result["placement_sd_mm"] = args.placement_sd_mm
    result.update(seconds=round(time.time() - start, 1), load_average=round(load, 2))
    return result


def print_result(result: dict, args):
    name, layout = result["variant"], result["layout"]
    if args.two_point_only:
        tp = result["two_point"]
        print(f"{name:28s} {layout:13s} placement sd {args.placement_sd_mm:g} mm two-point gradual share {tp['gradual_share']:.2f} "
              f"{tp['gradual_share_per_seed']}  distances {tp['discrimination_mm']}  "
              f"[{result['seconds']} s, load {result['load_average']}]", flush=True)
        return
    sp = result["single_point"]
    print(f"{name:28s} {layout:13s} {result['kind']:12s} loc {sp['localisation_mm'][0]:6.2f} ± {sp['localisation_mm'][1]:5.2f} "
          f"(per-frame sd {sp['localisation_sd_mm'][0]:5.2f})  4N {sp['by_force_mm'][4.0][0]:6.2f}  "
          f"10N {sp['by_force_mm'][10.0][0]:6.2f}  |F err| {sp['force_error_n'][0]:.2f} ± {sp['force_error_n'][1]:.2f}"
          f"  r {sp['force_r'][0]:.3f}  LOQ {sp['loq_kpa'][0]:.1f} kPa"
          + (f"  2pt gradual {result['two_point']['gradual_share']:.2f}" if args.two_point else "")
          + f"  [{result['seconds']} s, load {result['load_average']}]", flush=True)


def record_result(record, result: dict, args):
    """One record per test, so --kind and --two-point-only runs add to the default's rather than
    replace it: <variant>/<layout>/single_point/<kind>, <variant>/<layout>/two_point[/placement_sd_<sd>mm]."""
    add, remove, overrides, *_ = VARIANTS[result["variant"]]
    variant = {"variant": result["variant"], "layout": result["layout"], "effects_added": add,
               "effects_removed": list(remove), "scene_overrides": overrides,
               "seconds": result["seconds"], "load_average": result["load_average"]}
    base = f"{result['variant']}/{result['layout']}"
    if "single_point" in result:
        settings = reconstruction_settings(result["variant"], args.kind)
        record.add(f"{base}/single_point/{result['kind']}",
                   {**variant, "kind": result["kind"], "reconstruction": settings, **result["single_point"]},
                   seeds=args.seeds)
    if "two_point" in result:
        sd = args.placement_sd_mm
        record.add(f"{base}/two_point" + (f"/placement_sd_{sd:g}mm" if sd else ""),
                   {**variant, "placement_sd_mm": sd, **result["two_point"]}, seeds=args.seeds)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    parser.add_argument("--two-point", action="store_true", help="also run the two-point test")
    parser.add_argument("--two-point-only", action="store_true", help="run the two-point test alone")
    parser.add_argument("--placement-sd-mm", type=float, default=0.0,
                        help="two-point test: each indenter placed by hand to this sd per axis (mm)")
    parser.add_argument("--layouts", nargs="+", default=list(LAYOUTS), help="scene configs (default: both of the paper's)")
    parser.add_argument("--kind", default=None, help="reconstruction kind (models/ert/registry.py RECONSTRUCTIONS; "
                                                     "default: tikhonov)")
    parser.add_argument("--out", default=None)
    args = parser.parse_args()
    with recording("textile_layout_physics", MEASURED_CODE) as record:
        for name in args.variants:
            for layout in args.layouts:
                result = measure(name, layout, args)
                if args.out:
                    with open(args.out, "a") as handle:
                        handle.write(json.dumps(result) + "\n")
                print_result(result, args)
                record_result(record, result, args)


if __name__ == "__main__":
    main()
