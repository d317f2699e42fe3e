"""Choosing `learned_mlp`'s configuration on validation sensors, never on the bench's test sensors.

    OMP_NUM_THREADS=1 .venv/bin/python bench/ert_learned_validation.py --layout ert_boundary --noise-v 1e-3 \
        --members 7 --json members.json
    OMP_NUM_THREADS=1 .venv/bin/python bench/ert_learned_validation.py --layout ert_boundary --noise-v 1e-3 \
        --set n_training_sensors=160 --json sensors160.json

The validation sensors are simulated sensor instances of the scene (seeds 30,000-30,002 by
default) that are neither `learned_mlp`'s training sensors (seeds 20,000 + k) nor the bench's
test sensors (bench/ert_vs_pyeit.py, seeds 0-2). Each gets what a bench sensor gets: a
`calibration` recording (324 points x 2, 8.5, 15 N), on which the model chooses its noise weight as
in the bench, and a `single_point` recording (324 points x 4 and 10 N), here the validation
presses. The fit trains `--members` nets at the chosen weight; the mean of the first k of them
(k = 1 .. members; k = n_members is the model as configured, its first net the one that chose the
weight) is scored on the validation presses and on the calibration presses, so one run gives the
whole curve of error against ensemble size. `--set key=value` changes any other parameter of
models/ert/learned_readings_inverse.py (e.g. n_training_sensors=160, epochs=40).

Output: one line per sensor, k and force; a summary of mean +- sd over the sensors; --json; and
one record per layout, noise, --members and --set appended to results/ert_learned_validation.jsonl.
"""
import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.ert_vs_pyeit import recording, scene_cfg  # noqa: E402
# the module, not its `recording`: here a recording is a sensor's (calibration, single_point)
from common import result_records  # noqa: E402
from common.errors import InputError  # noqa: E402
from models.ert.learned_readings_inverse import MeanOfNets  # noqa: E402
from runs.studies.ert_tests import fit_reconstruction  # noqa: E402

VALIDATION_SEEDS = (30_000, 30_001, 30_002)
TEST_SEEDS = (0, 1, 2)    # the bench's sensors: never a validation sensor
# What the scores measure: learned_mlp (and the GREIT map and readings it builds on), the study
# that fits it, and the scene that simulates its training and validation sensors.
MEASURED_CODE = ["models/ert/", "runs/studies/ert_tests.py", "data/scenes/ert.py", "data/scenes/ert_effects.py",
                 "data/physics/sheet_conduction.py", "data/physics/press_update.py", "data/physics/textile_contact.py",
                 "data/ert/", "configs/scene/"]


def parsed_setting(text: str) -> tuple[str, object]:
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise InputError(f"--set takes key=value, got '{text}'")
    return key, json.loads(value)


def measure(args, cfg, params) -> list[dict]:
    """One row per validation sensor, ensemble size k and force, each printed as it comes."""
    rows = []
    for seed in args.seeds:
        cal = recording(cfg, seed, "calibration", [2.0, 15.0])
        val = recording(cfg, seed, "single_point", sorted(args.forces))
        start = time.process_time()
        model = fit_reconstruction("learned_mlp", cfg, seed, cal.channels, cal.targets, params)
        cpu_s = time.process_time() - start
        nets = list(model.module_.mlp.nets)
        usable = cal.targets[:, 2] >= model.quantification_limit_n
        for k in range(1, len(nets) + 1):
            model.module_.mlp = MeanOfNets(nets[:k])
            error = np.hypot(*(model.predict(val.channels)[:, :2] - val.targets[:, :2]).T)
            cal_mm = float(np.hypot(*(model.predict(cal.channels[usable])[:, :2] - cal.targets[usable, :2]).T).mean())
            for force in sorted(args.forces):
                at = val.targets[:, 2] == force
                rows.append({"layout": args.layout, "noise_v": args.noise_v, "seed": seed, "params": params,
                             "n_nets": k, "force_n": force, "localisation_mm": float(error[at].mean()),
                             "calibration_mm": cal_mm, "noise_weight": model.noise_weight_, "fit_cpu_s": cpu_s,
                             "load": os.getloadavg()[0]})
            print(f"seed {seed} nets {k}: " + ", ".join(f"{r['force_n']:g} N {r['localisation_mm']:.2f} mm"
                                                       for r in rows[-2:])
                  + f"; calibration {cal_mm:.2f} mm; weight {model.noise_weight_:g}; fit {cpu_s:.0f} s CPU; "
                  f"load {os.getloadavg()[0]:.2f}", flush=True)
    return rows


def print_summary(rows, args):
    print(f"\nload average at end {os.getloadavg()[0]:.2f}; mean ± sd over {len(args.seeds)} validation sensors")
    for k in sorted({r["n_nets"] for r in rows}):
        parts = []
        for force in sorted(args.forces):
            errors = np.array([r["localisation_mm"] for r in rows if r["n_nets"] == k and r["force_n"] == force])
            sd = errors.std(ddof=1) if len(errors) > 1 else 0.0
            parts.append(f"{force:g} N {errors.mean():.3f} ± {sd:.3f} mm")
        cal = np.array([r["calibration_mm"] for r in rows if r["n_nets"] == k and r["force_n"] == args.forces[0]])
        print(f"nets {k}: " + ", ".join(parts) + f"; calibration {cal.mean():.3f} mm")


def record_name(args) -> str:
    """The variant a record holds, e.g. ert_boundary/noise_0.001/members_7 or
    ert_boundary/noise_0.001/members_3/n_training_sensors=160."""
    return "/".join([args.layout, f"noise_{args.noise_v:g}", f"members_{args.members}", *sorted(args.set)])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--layout", default="ert_boundary")
    parser.add_argument("--noise-v", type=float, default=1e-3)
    parser.add_argument("--seeds", nargs="*", type=int, default=list(VALIDATION_SEEDS))
    parser.add_argument("--forces", nargs=2, type=float, default=[4.0, 10.0])
    parser.add_argument("--members", type=int, default=3, help="nets trained at the chosen noise weight")
    parser.add_argument("--set", nargs="*", default=[], help="other model parameters, key=value (value as JSON)")
    parser.add_argument("--scene-overrides", nargs="*", default=[], help="Hydra overrides of the scene (tests)")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args(argv)
    if set(args.seeds) & set(TEST_SEEDS):
        raise InputError(f"validation seeds {args.seeds} include the bench's test sensors {list(TEST_SEEDS)}")
    if args.members < 1:
        raise InputError(f"--members must be >= 1, got {args.members}")
    params = dict(parsed_setting(text) for text in args.set) | {"n_members": args.members}
    cfg = scene_cfg(args.layout, args.noise_v, args.scene_overrides)
    print(f"{args.layout} noise {args.noise_v:g} {params}; load average at start {os.getloadavg()[0]:.2f}", flush=True)
    # A scene shrunk by --scene-overrides (the tests') only prints: the records are the scene's own.
    with result_records.recording("ert_learned_validation", MEASURED_CODE) as record:
        rows = measure(args, cfg, params)
        if not args.scene_overrides:
            record.add(record_name(args), {"layout": args.layout, "noise_v": args.noise_v, "params": params,
                                           "forces_n": sorted(args.forces), "rows": rows}, seeds=args.seeds)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    print_summary(rows, args)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except InputError as problem:   # a bad option: one line, exit code 2, as train.py answers
        print(f"error: {problem}", file=sys.stderr)
        sys.exit(2)
