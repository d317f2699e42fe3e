"""How soon a large table shows progress, and how long each logged phase takes.

    .venv/bin/python bench/large_table.py                  # 2,000,000 rows (~520 MB), three runs
    .venv/bin/python bench/large_table.py --rows 200000 --runs 1

Writes a CSV of the default rubber12 scene (seed 0, 450 presses) repeated to `--rows` rows, each
channel and the pressure jittered by 0.1 % (numpy seed 0) so that no two rows repeat, into a
temporary folder; then runs `train.py data=table` on it `--runs` times, one thread, export off,
reads the log as it arrives and stops each run once its features are computed. Prints, per run
and as mean ± sd: seconds from the command's start to the `reading` line, the read, the check and
split (the read's line to the `data split` line), the features, and the run's CPU time so far.
Appends every run's phases to results/large_table.jsonl (record `phases_<rows>_rows`).
"""
import argparse
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402
from common.spread import format_mean_sd  # noqa: E402

# What a large table goes through up to its features: train.py and the run it starts, the
# reader and its checks, the split, the datamodule and its features.
MEASURED_CODE = ["train.py", "runs/run.py", "data/readers/", "data/sensor_table.py", "data/units.py", "data/splits/",
                 "data/datamodules/regression.py", "data/preprocessing/", "common/progress.py"]


def write_table(path: Path, rows: int) -> None:
    from hydra import compose, initialize_config_dir
    from hydra.utils import instantiate
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        presses = instantiate(compose("config", overrides=["scene=rubber12", "seed=0"]).scene).generate().frame
    table = presses.iloc[np.arange(rows) % len(presses)].reset_index(drop=True)
    rng = np.random.default_rng(0)
    for column in [c for c in table.columns if c.startswith("r_")] + ["pressure_pa"]:
        table[column] = table[column] * (1 + 1e-3 * rng.standard_normal(rows))
    table.to_csv(path, index=False)


def one_run(csv: Path, out: Path) -> dict:
    """Seconds per phase of one `train.py` run on `csv`, stopped after its features."""
    command = [sys.executable, "-u", str(ROOT / "train.py"), "data=table", f"data.path={csv}",
               "data.target_columns=[x_mm,y_mm,depth_mm,pressure_pa]", "data.group_columns=[x_mm,y_mm,depth_mm]",
               "threads=1", "export=none", f"hydra.run.dir={out}"]
    env = dict(os.environ, CI="true", OMP_NUM_THREADS="1", PYTHONUNBUFFERED="1")
    cpu_before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    run = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    phases = {}
    for line in run.stdout:
        now = time.perf_counter() - start
        if f"reading {csv.name}" in line and line.rstrip().endswith("...") and "first_line" not in phases:
            phases["first_line"] = now
        read = re.search(rf"reading {re.escape(csv.name)} .*rows in ([\d.]+) s", line)
        if read:
            phases["read"], read_line = float(read.group(1)), now
        if "data split:" in line and "read" in phases:
            phases["check_and_split"] = now - read_line
        features = re.search(r"features of [\d,]+ rows: done in ([\d.]+) s", line)
        if features:
            phases["features"] = float(features.group(1))
            break
    run.terminate()
    run.wait()
    cpu = resource.getrusage(resource.RUSAGE_CHILDREN)
    phases["cpu"] = (cpu.ru_utime + cpu.ru_stime) - (cpu_before.ru_utime + cpu_before.ru_stime)
    missing = {"first_line", "read", "check_and_split", "features"} - set(phases)
    if missing:
        sys.exit(f"large_table: the run's log lacked {', '.join(sorted(missing))} (see {out})")
    return phases


def timed_runs(rows: int, count: int) -> tuple[list[dict], float]:
    """Each run's seconds per phase on a fresh table of `rows` rows, and the table's size in MB."""
    with tempfile.TemporaryDirectory(prefix="touchstone-large-table-") as folder:
        csv = Path(folder) / "rig.csv"
        write_table(csv, rows)
        size_mb = csv.stat().st_size / 1e6
        print(f"{csv.name}: {rows:,} rows, {size_mb:.1f} MB; load {os.getloadavg()[0]:.2f}")
        runs = []
        for index in range(count):
            runs.append(one_run(csv, Path(folder) / f"run{index}"))
            print(f"run {index}: " + ", ".join(f"{k} {v:.2f} s" for k, v in runs[-1].items()), flush=True)
    print("mean ± sd: " + ", ".join(f"{k} {format_mean_sd([r[k] for r in runs])} s" for k in runs[0])
          + f"; load {os.getloadavg()[0]:.2f}")
    return runs, size_mb


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rows", type=int, default=2_000_000)
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args(argv)
    if args.rows < 1000 or args.runs < 1:
        print("large_table: --rows must be >= 1000 and --runs >= 1", file=sys.stderr)
        sys.exit(2)
    with recording("large_table", MEASURED_CODE) as record:
        runs, size_mb = timed_runs(args.rows, args.runs)
        # The size is in the name: a quick run on a small table does not stand in for the default's.
        record.add(f"phases_{args.rows}_rows",
                   {"rows": args.rows, "size_mb": size_mb, "threads": 1, "scene": "rubber12",
                    **{f"{phase}_s_by_run": [run[phase] for run in runs] for phase in runs[0]}},
                   seeds=[0])


if __name__ == "__main__":
    main()
