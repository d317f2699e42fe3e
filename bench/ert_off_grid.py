"""ERT localisation on the calibration grid and off it (issue 42), per layout and reconstruction.

    .venv/bin/python bench/ert_off_grid.py                                  # Tikhonov, both layouts, 10 and 4 N
    .venv/bin/python bench/ert_off_grid.py --kinds tikhonov greit --forces 10
    .venv/bin/python bench/ert_off_grid.py --seeds 0 --presses 100          # quicker

For each layout (scene=ert_boundary, ert_internal) and sensor seed the calibration recording is
the one `experiment=ert_localisation` takes; the same calibrated reconstruction then localises the
paper's 324 grid points and as many presses at random positions off the grid
(runs/studies/ert_off_grid.py), at each force. Prints the mean localisation error per seed as
mean ± sd over seeds and appends one record per layout, kind and force to results/ert_off_grid.jsonl.
Not measured here: pyEIT's JAC/GREIT on the same off-grid frames (bench/ert_vs_pyeit.py measures
them on the grid) and a Bayesian bound.
"""
import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydra import compose, initialize_config_dir  # noqa: E402
from omegaconf import OmegaConf  # noqa: E402

from common.result_records import recording  # noqa: E402
from common.spread import format_mean_sd  # noqa: E402
from common.threads import apply_threads, configured_threads  # noqa: E402
from runs.studies.ert_off_grid import off_grid_study  # noqa: E402

LAYOUTS = ("ert_boundary", "ert_internal")
MEASURED_CODE = ["runs/studies/ert_off_grid.py", "runs/studies/ert_tests.py", "models/ert/", "data/ert/",
                 "data/scenes/ert.py", "data/scenes/ert_effects.py", "configs/scene/", "configs/experiment/"]


def experiment(layout: str):
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        return compose("config", overrides=["experiment=ert_localisation", f"scene={layout}"])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--layouts", nargs="*", default=list(LAYOUTS), choices=LAYOUTS)
    parser.add_argument("--kinds", nargs="*", default=["tikhonov"], help="reconstructions (models/ert/registry.py)")
    parser.add_argument("--forces", type=float, nargs="*", default=[10.0, 4.0])
    parser.add_argument("--seeds", type=int, nargs="*", default=[0, 1, 2])
    parser.add_argument("--presses", type=int, default=324, help="off-grid presses per seed and force")
    args = parser.parse_args(argv)
    apply_threads(configured_threads() or 1)
    print("| layout | reconstruction | force | on the grid (mm) | off the grid (mm) | off-grid presses' distance "
          "to the grid (mm) | seconds |\n|---|---|---|---|---|---|---|")
    with recording("ert_off_grid", MEASURED_CODE) as record:
        for layout in args.layouts:
            cfg = experiment(layout)
            study = OmegaConf.to_container(cfg.study, resolve=True)
            for kind in args.kinds:
                start = time.perf_counter()
                frame = off_grid_study(cfg, tuple(args.seeds), study["calibration"],
                                       {**study["reconstruction"], "kind": kind}, tuple(args.forces), args.presses)
                seconds = time.perf_counter() - start
                for force in args.forces:
                    at = frame[frame.force_n == force]
                    per_seed = at.groupby(["placement", "seed"]).error_mm.mean()
                    on, off = per_seed["on_grid"].to_numpy(), per_seed["off_grid"].to_numpy()
                    distance = at[at.placement == "off_grid"].grid_distance_mm
                    print(f"| {layout} | {kind} | {force:g} N | {format_mean_sd(on)} | {format_mean_sd(off)} | "
                          f"{distance.median():.1f} (median) | {seconds:.0f} |", flush=True)
                    record.add(f"{layout}/{kind}/{force:g}n",
                               {"layout": layout, "kind": kind, "force_n": force, "on_grid_mm": on.tolist(),
                                "off_grid_mm": off.tolist(), "off_grid_presses": args.presses,
                                "grid_distance_median_mm": float(distance.median()), "seconds_all_forces": seconds},
                               seeds=args.seeds)


if __name__ == "__main__":
    main()
