"""Contact tracker speed: p50 and p99 of `ContactTracker.update` per frame, one thread, at 0, 1
and 5 contacts on 6 x 6 and 12 x 21 frames, ours beside the paper's algorithm (seed 001 reports
404.7 us per frame without contact and 627.2 us with 5 +/- 3 contacts, 12 x 21, its machine).

    OMP_NUM_THREADS=1 .venv/bin/python bench/contacts.py
    OMP_NUM_THREADS=1 .venv/bin/python bench/contacts.py --frames 4000 --repeats 5 --grids 12x21

Frames: a rest level with per-cell offsets and Gaussian noise (sigma 1.6 counts, the scene's
baseline noise) plus k Gaussian bumps (peak 40-120 counts, 0.7 pitch wide) drifting slowly in
separate lanes, so the ids persist and the tracker does its usual per-frame work. The timing
covers `update` only (the call an application makes per frame), after a warm-up; each figure is
the median over --repeats runs of the per-run p50 / p99.
"""
import argparse
import os
import sys
import time
from pathlib import Path

for variable in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ.setdefault(variable, "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from models.contact_tracker import ContactTracker  # noqa: E402

PAPER_US = {0: 404.7, 5: 627.2}
CONFIGS = {"ours": dict(),
           "paper": dict(threshold="variance", segmentation="paper", tracking="paper")}


def synthetic_stream(rows, cols, n_contacts, n_frames, n_rest=60, pitch_mm=6.0, seed=0):
    """(rest frames, live frames) with n_contacts drifting bumps in the live frames."""
    rng = np.random.default_rng(seed)
    offset = 1240.0 + rng.normal(0.0, 40.0, (rows, cols))
    rest = offset + rng.normal(0.0, 1.6, (n_rest, rows, cols))
    live = offset + rng.normal(0.0, 1.6, (n_frames, rows, cols))
    if n_contacts:
        yy, xx = np.mgrid[0:rows, 0:cols]
        t = np.arange(n_frames)[:, None, None]
        lanes = np.linspace(0.5, rows - 1.5, n_contacts)
        for k in range(n_contacts):
            # spread the contacts over the grid: columns apart, rows apart where the grid allows
            x0 = (k + 0.5) * cols / n_contacts
            y0 = lanes[k] if rows >= 2 * n_contacts else (k % 2) * (rows - 2) + 1.0
            x = x0 + 0.6 * np.sin(2 * np.pi * t / 240.0 + k)
            peak = rng.uniform(40.0, 120.0)
            live += peak * np.exp(-((xx - x) ** 2 + (yy - y0) ** 2) / (2 * 0.7 ** 2))
    return rest, live


def time_updates(tracker, live) -> np.ndarray:
    clock = time.perf_counter_ns
    elapsed = np.empty(len(live))
    for i, frame in enumerate(live):
        start = clock()
        tracker.update(frame)
        elapsed[i] = clock() - start
    return elapsed / 1e3


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=2000, help="timed frames per run")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--grids", nargs="*", default=["6x6", "12x21"])
    parser.add_argument("--contacts", nargs="*", type=int, default=[0, 1, 5])
    args = parser.parse_args(argv)
    print(f"load average at start: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores (shared machines inflate every figure)\n")
    print("| grid | contacts | tracker | found per frame | p50 (us) | p99 (us) | paper (us, its machine) |")
    print("|---|---|---|---|---|---|---|")
    for grid in args.grids:
        rows, cols = map(int, grid.split("x"))
        for k in args.contacts:
            rest, live = synthetic_stream(rows, cols, k, args.frames + 200)
            for name, params in CONFIGS.items():
                p50s, p99s = [], []
                for _ in range(args.repeats):
                    tracker = ContactTracker(rows=rows, cols=cols, pitch_mm=6.0, **params).fit(rest)
                    time_updates(tracker, live[:200])  # warm-up: imports, caches
                    elapsed = time_updates(tracker, live[200:])
                    p50s.append(np.percentile(elapsed, 50))
                    p99s.append(np.percentile(elapsed, 99))
                found = np.mean([len(tracker.update(f)) for f in live[:50]])
                paper = PAPER_US.get(k, "") if grid == "12x21" and name == "paper" else ""
                print(f"| {grid} | {k} | {name} | {found:.1f} | {np.median(p50s):.1f} | {np.median(p99s):.1f} | {paper} |",
                      flush=True)
    print(f"\nload average at end: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
