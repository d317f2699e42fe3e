"""How long the default test suite takes (`make test`: pytest -m "not slow" -n 2), on an idle
machine and beside one busy process, recorded so the README states it from a record.

    .venv/bin/python bench/test_suite_time.py --runs 3                 # idle: nothing else should run
    .venv/bin/python bench/test_suite_time.py --runs 3 --beside-busy   # beside one process spinning a core

The busy process is a Python loop on one core for the whole run: what a user's other job (a
training run, a browser) takes from a 2-core machine. One record per command: each run's wall
time and the counts pytest printed (passed, failed, skipped, ...), and the load before and after;
a run with failures is recorded too (its counts say so) but the command exits 1. Goals (issue 45):
<= 8 min idle, <= 15 min beside one busy process.
"""
import argparse
import re
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402

SUITE = [sys.executable, "-m", "pytest", "-q", "-m", "not slow", "-n", "2", "-p", "no:cacheprovider"]
MEASURED = ["tests/", "common/", "data/", "models/", "export/", "runs/", "configs/", "train.py", "predict.py"]
SPINNER = "while True: pass"
COUNTS = re.compile(r"(\d+) (passed|failed|skipped|xfailed|xpassed|errors?|warnings?)")


def run_suite(beside_busy: bool) -> dict:
    """One run of the default suite: wall seconds and pytest's summary counts."""
    busy = subprocess.Popen([sys.executable, "-c", SPINNER]) if beside_busy else None
    try:
        start = time.perf_counter()
        suite = subprocess.Popen(SUITE, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        lines = []
        for line in suite.stdout:        # pytest's progress, passed through as it comes
            print(line, end="", flush=True)
            lines.append(line)
        suite.wait()
        wall_s = time.perf_counter() - start
    finally:
        if busy is not None:
            busy.kill()
            busy.wait()
    summary = next((line.strip() for line in reversed(lines) if COUNTS.search(line)), "")
    counts = {kind.rstrip("s") if kind.startswith("error") else kind: int(n) for n, kind in COUNTS.findall(summary)}
    return {"wall_s": wall_s, "counts": counts, "summary": summary, "exit_code": suite.returncode}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--beside-busy", action="store_true", help="run it beside one process spinning a core")
    parser.add_argument("--runs", type=int, default=3, help="runs of the suite, one after the other")
    args = parser.parse_args(argv)
    name = "beside_one_busy_process" if args.beside_busy else "idle"
    results = []
    with recording("test_suite", MEASURED) as record:
        for run in range(1, args.runs + 1):
            print(f"run {run} of {args.runs} of the default test suite ({name}): pytest's progress follows", flush=True)
            results.append(run_suite(args.beside_busy))
            print(f"run {run}: {results[-1]['wall_s'] / 60:.1f} min; {results[-1]['summary']}", flush=True)
        record.add(name, {"wall_s": [r["wall_s"] for r in results], "counts": [r["counts"] for r in results],
                          "exit_code": [r["exit_code"] for r in results]}, seeds=list(range(args.runs)))
    print(f"{name}: " + ", ".join(f"{r['wall_s'] / 60:.1f}" for r in results) + " min")
    return 0 if all(r["exit_code"] == 0 for r in results) else 1

if __name__ == "__main__":
    sys.exit(main())
