"""The README's quick tour, timed: each command as a user types it, over seeds, wall and CPU time,
and the default run's scores and choice per seed; appended to results/quick_tour.jsonl.

    .venv/bin/python bench/quick_tour.py --quick      # the headline commands (make bench-quick)
    .venv/bin/python bench/quick_tour.py              # every command of the tour (make bench)
    .venv/bin/python bench/quick_tour.py --only default extra_trees --seeds 0

Each command runs in its own process as `CI=true python <command> seed=<s>` with a fresh run folder
under a temporary directory, one after another (nothing else of this bench runs beside it); wall
time is the whole command (start-up, export, report), CPU time is the child's user + sys. The
README's tour table and docs/pipeline.md's default-run table are drawn from these records.
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402

# (name, arguments after `python`, what it does in a few words, in the quick subset). A command
# with {seed} gets each seed; {run} is the default run's folder of the same seed (predict reads it).
TOUR = [
    ("default", ["train.py", "seed={seed}"],
     "the default: rubber12, 450 simulated presses, model chosen on validation, ONNX", True),
    ("extra_trees", ["train.py", "model=extra_trees", "seed={seed}"], "one forest, quick: metrics, figures, ONNX", True),
    ("resmlp", ["train.py", "model=resmlp", "seed={seed}"], "the rubber12 paper's residual MLP alone", True),
    ("predict", ["predict.py", "model={run}/model.onnx", "input={run}/predictions.csv", "output={tmp}/pred.csv"],
     "predict with the exported ONNX file alone", True),
    ("taxel_receptive_field", ["train.py", "experiment=taxel_receptive_field", "seed={seed}"],
     "taxels: strain profiles and receptive field vs cover thickness", True),
    ("ert_localisation", ["train.py", "experiment=ert_localisation", "scene=ert_internal", "seed={seed}"],
     "ERT skin: the paper's Tikhonov localisation over its 324 points, beside GREIT checked on validation sensors", True),
    ("materials10", ["train.py", "experiment=materials10", "seed={seed}"],
     "fingertip surface recognition, PR-CNN, unseen force levels held out", False),
    ("sweep", ["train.py", "-m", "model=extra_trees,decision_tree", "seed={seed}"],
     "a sweep of two models ending in a Pareto report", False),
    ("capacitive_tracking", ["train.py", "experiment=capacitive_tracking", "seed={seed}"],
     "capacitive skin: track contacts, MOTA/IDF1, force per contact", False),
    ("capacitive_force_svr", ["train.py", "experiment=capacitive_force", "hydra.mode=RUN", "model=svr", "seed={seed}"],
     "force from capacitance with the paper's linear SVR", False),
    ("taxels_load_inverse", ["train.py", "scene=taxels", "scene.protocol=random_loads", "model=extra_trees",
                             "seed={seed}"], "taxels: position, normal and shear force from readings", False),
]
# The code a tour command exercises: the whole library, its configs and the entry points.
MEASURED_CODE = ["common/", "data/", "models/", "export/", "runs/", "configs/", "train.py", "predict.py"]


def run_command(arguments: list[str], folder: Path) -> tuple[float, float]:
    """Wall and CPU seconds of one command in its own process, its run folder `folder`."""
    multirun = "-m" in arguments
    folder_setting = f"hydra.sweep.dir={folder}" if multirun else f"hydra.run.dir={folder}"
    command = [sys.executable, *arguments] + ([folder_setting] if arguments[0] == "train.py" else [])
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, cwd=ROOT, env={**os.environ, "CI": "true"}, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        tail = (done.stderr or done.stdout).strip().splitlines()[-3:]
        raise SystemExit(f"quick_tour: `{' '.join(arguments)}` exited {done.returncode}: {' | '.join(tail)}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def display(arguments: list[str]) -> str:
    """The command as the README shows it: no seed, placeholders for the run folder."""
    shown = [a.replace("{run}", "<run>").replace("{tmp}/", "") for a in arguments if a != "seed={seed}"]
    return "python " + " ".join(shown)


def default_scores(metrics: dict) -> dict:
    """What the default run printed and chose: the numbers a fresh clone must reproduce."""
    choice = metrics["choice"]
    return {"chosen": choice["chosen"],
            "validation_r2": {name: scores["r2"] for name, scores in choice["validation"].items()},
            "test_r2_over_splits": {target: metrics["spread"]["test"][target]["r2"]
                                    for target in metrics["spread"]["test"]},
            "n_splits": metrics["spread"]["splits"]}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="the headline commands only")
    parser.add_argument("--only", nargs="+", choices=[name for name, *_ in TOUR])
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    args = parser.parse_args(argv)
    chosen = [row for row in TOUR if (args.only is None or row[0] in args.only) and (row[3] or not args.quick)]
    if "predict" in [row[0] for row in chosen] and "default" not in [row[0] for row in chosen]:
        chosen.insert(0, TOUR[0])     # predict reads the default run's folder
    with tempfile.TemporaryDirectory(prefix="quick_tour-") as tmp, recording("quick_tour", MEASURED_CODE) as record:
        for name, arguments, what, _ in chosen:
            wall, cpu, scores, metrics = [], [], [], []
            for seed in args.seeds:
                folder = Path(tmp) / f"{name}-{seed}"
                filled = [a.format(seed=seed, run=Path(tmp) / f"default-{seed}", tmp=tmp) for a in arguments]
                seconds = run_command(filled, folder)
                wall.append(round(seconds[0], 2))
                cpu.append(round(seconds[1], 2))
                print(f"{name} seed {seed}: {seconds[0]:.1f} s wall, {seconds[1]:.1f} s CPU, "
                      f"load {os.getloadavg()[0]:.1f}", flush=True)
                written = folder / "metrics.json"
                if written.is_file():       # a run's own scores: what a fresh clone must reproduce
                    written = json.loads(written.read_text())
                    metrics.append({part: written[part] for part in ("val", "test") if part in written})
                    if name == "default":
                        scores.append(default_scores(written))
            record.add(name, {"command": display(arguments), "what": what, "wall_s": wall, "cpu_s": cpu,
                              "quick": name in [row[0] for row in TOUR if row[3]], "metrics_by_seed": metrics},
                       seeds=args.seeds)
            if scores:
                record.add("default_scores", {"by_seed": scores}, seeds=args.seeds)


if __name__ == "__main__":
    main()
