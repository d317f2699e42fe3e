"""Threads benchmark: three workloads on an idle machine and beside one CPU-bound process, with
every library's default thread count (`threads=all`) and with Touchstone's
default (`threads=1`). The slowdown is loaded / idle wall time.

    .venv/bin/python bench/threads.py                      # all workloads, ~10 min on 2 cores
    .venv/bin/python bench/threads.py --workloads prcnn_epoch --repeats 1

Workloads: `default_run` = `python train.py` (the blend pipeline, export and latency included),
`resmlp_run` = `python train.py model=resmlp`, `prcnn_epoch` = one PR-CNN training epoch on
2,000 windows of the fingertip's shape (2 channels x 140 steps, batch 128), timed in-process
after start-up. The competing process is a pure-Python busy loop (one core). Appends the wall
times per run to results/threads.jsonl (common/result_records.py).
"""
import argparse
import os
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

SEED = 0   # train.py's default seed (configs/config.yaml) and the PR-CNN epoch's data
# What the wall times measure: the thread setting and the pipeline each workload runs under it.
MEASURED_CODE = ["common/", "data/", "models/", "export/", "runs/", "configs/", "train.py"]
WORKLOADS = {
    "default_run": [sys.executable, "train.py", "hydra.run.dir={out}"],
    "resmlp_run": [sys.executable, "train.py", "model=resmlp", "hydra.run.dir={out}"],
    "prcnn_epoch": [sys.executable, "bench/threads.py", "--child-prcnn-epoch"],
}


def prcnn_epoch() -> None:
    """One PR-CNN epoch, configured as experiment=materials10 composes it; prints its seconds."""
    import numpy as np
    from hydra import compose, initialize_config_dir
    from hydra.utils import instantiate

    from common.threads import apply_threads, resolve_threads
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose("config", overrides=["experiment=materials10", "trainer.max_epochs=1",
                                           "trainer.progress=false", "trainer.device=cpu"])
    apply_threads(resolve_threads(os.environ.get("TOUCHSTONE_THREADS", "1")))
    rng = np.random.default_rng(SEED)
    X = rng.standard_normal((2000, 2, 140)).astype(np.float32)
    y = rng.integers(0, 10, 2000)
    model = instantiate(cfg.model, modalities={"triboelectric": [0], "piezoresistive": [1]})
    start = time.perf_counter()
    model.fit(X, y)
    print(f"{time.perf_counter() - start:.3f}")


def wall_time(workload: str, threads: str, out: Path) -> float:
    out = Path(tempfile.mkdtemp(dir=out))  # a fresh run folder per run
    command = [part.format(out=out / "run") for part in WORKLOADS[workload]]
    env = dict(os.environ, TOUCHSTONE_THREADS=threads, CI="true")
    for name in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        env.pop(name, None)  # `all` must mean every library's own default
    start = time.perf_counter()
    done = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"{workload} failed: {done.stderr.strip().splitlines()[-1:]}")
    return float(done.stdout.strip().splitlines()[-1]) if workload == "prcnn_epoch" else seconds


def measure(workload: str, threads: str, repeats: int, out: Path) -> tuple:
    """One workload at one thread setting, idle and beside a busy process: its wall times per run."""
    times = {}
    for load in ("idle", "one busy process"):
        busy = subprocess.Popen([sys.executable, "-c", "while True: pass"]) if load != "idle" else None
        try:
            times[load] = np.array([wall_time(workload, threads, out) for _ in range(repeats)])
        finally:
            if busy is not None:
                busy.kill()
                busy.wait()
    print(f"{workload:12s} threads={threads:3s} idle {format_mean_sd(times['idle'], '.1f', one_value='{}')} s   "
          f"beside one busy process {format_mean_sd(times['one busy process'], '.1f', one_value='{}')} s   "
          f"slowdown {times['one busy process'].mean() / times['idle'].mean():.2f}x", flush=True)
    return workload, threads, times["idle"], times["one busy process"]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--workloads", nargs="*", default=list(WORKLOADS))
    parser.add_argument("--repeats", type=int, default=1, help="runs per cell (mean ± sd when more than one)")
    parser.add_argument("--child-prcnn-epoch", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child_prcnn_epoch:
        return prcnn_epoch()
    out = ROOT / "outputs" / "bench_threads"
    out.mkdir(parents=True, exist_ok=True)
    with recording("threads", MEASURED_CODE) as record:
        rows = [measure(workload, threads, args.repeats, out)
                for workload in args.workloads for threads in ("all", "1")]
        print("\n| workload | threads | idle (s) | beside one busy process (s) | slowdown |\n|---|---|---|---|---|")
        for workload, threads, idle, loaded in rows:
            print(f"| {workload} | {threads} | {format_mean_sd(idle, '.1f', one_value='{}')} | "
                  f"{format_mean_sd(loaded, '.1f', one_value='{}')} | {loaded.mean() / idle.mean():.2f}x |")
        record.add("slowdown", {"repeats": args.repeats, "cores": os.cpu_count(), "busy_processes": 1,
                                "timed": "the command's wall time; prcnn_epoch: the epoch alone, in-process",
                                "rows": [{"workload": w, "threads": t, "idle_s": idle, "loaded_s": loaded}
                                         for w, t, idle, loaded in rows]}, seeds=[SEED])


if __name__ == "__main__":
    main()
