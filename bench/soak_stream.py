"""Soak: every kind of exported model on a long live stream through predict.py, one thread.

    OMP_NUM_THREADS=1 .venv/bin/python bench/soak_stream.py                      # the issue's counts
    OMP_NUM_THREADS=1 .venv/bin/python bench/soak_stream.py --lines 200000 --windows 20000 --frames 100000

For each kind, a model is trained on a scene and exported as a run does (once per seed, small settings:
the soak measures the stream, not the model's accuracy):
- table: a residual MLP on the default scene (rubber12's presses), one prediction per line;
- recordings: MiniRocket on materials10 (fingertip recordings), one prediction per hop of the
  sliding window (--hop steps);
- tracker: the capacitive skin's force model on the 3 x 3 window (linear regression), and the
  contact tracker on the scene's own stream, one line per frame.
Then `predict.py model=... input=- backlog=wait threads=1` reads a generated stream from a file
(the scene's readings cycled to the count), writes every prediction to a CSV and its summary
to JSON, while this script samples its resident memory (VmRSS) and thread count four times a
second. Recorded per kind: the lines in and predictions out (lost = expected - distinct lines
out, duplicated = rows - distinct), the resident memory once the first 10 % of the output was
written (after warm-up) and at the last sample before the end, the p50 and p99 of latency_us over the first and the last 10 %
of predictions, the loop's own cost per prediction (the per-prediction overhead goal): the run's wall time per
prediction minus the model's mean wall time per call, and the same in CPU time (the process's
CPU time minus the model calls' thread CPU time), which a busy machine does not inflate by the
time the process waits for a core; and the summary.
Goals (issue 44): memory growth <= 5 MB, p99 drift <= 10 %, 0 lost, overhead <= 50 µs (table).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydra import compose, initialize_config_dir  # noqa: E402
from hydra.utils import instantiate  # noqa: E402

from common.result_records import recording  # noqa: E402
from export.onnx_predictor import OnnxPredictor  # noqa: E402
from export.run_export import export_run  # noqa: E402
from models.deployable import load_pipeline  # noqa: E402
from runs.run import run  # noqa: E402

# What the soak measures: the live loop and what it calls per line (not the --plot view, which it does not draw).
MEASURED_CODE = ["predict.py", "export/onnx_predictor.py", "export/window_force.py", "data/readers/stream_lines.py",
                 "models/contact_tracking/"] \
    + [f"export/live/{name}.py" for name in ("sources", "backlog", "kinds", "loop", "writer", "summary")]
OVERRIDES = {
    "table": ["model=resmlp", "scene.progress=false", "trainer.progress=false", "trainer.max_epochs=20",
              "analysis.ablation=false", "analysis.progress=false"],
    "recordings": ["experiment=materials10", "model=minirocket", "scene.passes_per_level=2",
                   "trainer.progress=false"],
    "tracker": ["experiment=capacitive_force", "hydra.mode=RUN", "model=linear_regression",
                "scene.characterisation_channels=window"],
}
SAMPLE_S = 0.25
FIGURE = ROOT / "bench" / "figures" / "live_plot.png"


def compose_run(kind: str, seed: int):
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        return compose("config", overrides=OVERRIDES[kind] + [f"seed={seed}"])


def train(kind: str, seed: int, folder: Path) -> tuple[Path, np.ndarray, list[str], int]:
    """The exported model, the readings a stream repeats (one row per line), predict.py's extra
    arguments, and the leading lines that are not predicted (the tracker's rest frames)."""
    cfg = compose_run(kind, seed)
    run(cfg, folder)
    model = export_run(folder)
    pipeline = load_pipeline(folder / "pipeline.npz")
    if kind == "table":
        return model, np.asarray(pipeline.examples, dtype=np.float64), [], 0
    if kind == "recordings":   # each window's steps, in time order: the stream of a sensor at its rate
        windows = np.asarray(pipeline.examples, dtype=np.float64)          # (n, channels, steps)
        return model, windows.transpose(0, 2, 1).reshape(-1, windows.shape[1]), [], 0
    scene = instantiate(cfg.scene, protocol="stream")
    stream = scene.stream()
    rest = stream.frames[:stream.n_rest_frames].reshape(stream.n_rest_frames, -1)
    live = stream.frames[stream.n_rest_frames:].reshape(len(stream.frames) - stream.n_rest_frames, -1)
    args = [f"rows={stream.rows}", f"cols={stream.cols}", f"pitch_mm={stream.pitch_mm}",
            f"n_rest_frames={stream.n_rest_frames}"]
    return model, np.concatenate([rest, live]), args, stream.n_rest_frames


def write_lines(path: Path, readings: np.ndarray, n: int, keep_first: int) -> None:
    """n lines: the first `keep_first` rows once (rest frames), then the rest cycled."""
    lines = [",".join(f"{v:.6g}" for v in row) for row in readings]
    head, body = lines[:keep_first], lines[keep_first:]
    block, left = "\n".join(body) + "\n", n - keep_first
    with open(path, "w") as file:
        file.write("".join(line + "\n" for line in head))
        while left >= len(body):
            file.write(block)
            left -= len(body)
        if left:
            file.write("\n".join(body[:left]) + "\n")


def sample_memory(pid: int, output: Path, samples: list, stop: threading.Event) -> None:
    """(bytes of output written, VmRSS in kB, threads) of process `pid` every SAMPLE_S until it
    ends: progress is the output's size, so warm-up is a share of the predictions, not of time."""
    partial = output.with_name(output.name + ".partial")
    while not stop.is_set():
        try:
            status = Path(f"/proc/{pid}/status").read_text()
            written = partial.stat().st_size if partial.exists() else 0
        except OSError:
            return
        fields = dict(line.split(":", 1) for line in status.splitlines() if ":" in line)
        if "VmRSS" in fields:
            samples.append((written, int(fields["VmRSS"].split()[0]), int(fields["Threads"].strip())))
        stop.wait(SAMPLE_S)


def soak(model: Path, lines_file: Path, args: list[str], folder: Path, hop: int | None) -> dict:
    """predict.py on the stream; its figures (see the module's doc)."""
    output, summary = folder / "out.csv", folder / "summary.json"
    command = [sys.executable, str(ROOT / "predict.py"), f"model={model}", "input=-", "backlog=wait", "threads=1",
               f"output={output}", f"summary={summary}", *args] + ([f"hop={hop}"] if hop else [])
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    samples, stop = [], threading.Event()
    with open(lines_file, "rb") as stdin:
        process = subprocess.Popen(command, stdin=stdin, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                   env=env, cwd=ROOT)
        watcher = threading.Thread(target=sample_memory, args=(process.pid, output, samples, stop))
        watcher.start()
        _, err = process.communicate()
        stop.set()
        watcher.join()
    if process.returncode:
        raise SystemExit(f"predict.py failed ({process.returncode}): {err.decode()[-500:]}")
    figures = json.loads(summary.read_text())
    out = pd.read_csv(output, usecols=["line", "latency_us"])
    latency, n = out["latency_us"].to_numpy(), len(out)
    tenth = max(n // 10, 1)
    first, last = latency[:tenth], latency[-tenth:]
    size = output.stat().st_size
    warm = [kb for written, kb, _ in samples if 0 < written and written >= 0.1 * size]   # after the first 10 %
    return {"predictions": n, "distinct_lines": int(out["line"].nunique()),
            "duplicated": int(n - out["line"].nunique()),
            "rss_after_warmup_mb": warm[0] / 1024 if warm else None, "rss_end_mb": warm[-1] / 1024 if warm else None,
            "rss_peak_mb": max(kb for _, kb, _ in samples) / 1024 if samples else None,
            "most_threads": max(t for _, _, t in samples) if samples else None,
            "p50_first_us": float(np.percentile(first, 50)), "p50_last_us": float(np.percentile(last, 50)),
            "p99_first_us": float(np.percentile(first, 99)), "p99_last_us": float(np.percentile(last, 99)),
            "overhead_us": (figures["wall_us_per_prediction"] - figures["model_us"]["mean"]
                            * figures["model_us"]["calls"] / max(figures["predicted"], 1)),
            "overhead_cpu_us": (figures["cpu_us_per_prediction"] - figures["model_us"]["cpu_mean"]
                                * figures["model_us"]["calls"] / max(figures["predicted"], 1)),
            "summary": figures, "stderr_tail": err.decode().strip().splitlines()[-2:]}


def draw_live_view(model: Path, lines_file: Path, args: list[str], png: Path, n: int = 1500) -> None:
    """predict.py's live view (plot_file=, the --plot figure) of the stream's first n lines."""
    with open(lines_file) as file:
        head = "".join(line for _, line in zip(range(n), file))
    subprocess.run([sys.executable, str(ROOT / "predict.py"), f"model={model}", "input=-", "threads=1",
                    f"plot_file={png}", *args], input=head, text=True, check=True,
                   capture_output=True, cwd=ROOT)


def expected_predictions(kind: str, n_lines: int, window: int, hop: int, rest: int) -> int:
    if kind == "recordings":
        return (n_lines - window) // hop + 1
    return n_lines - rest


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--kinds", nargs="*", default=list(OVERRIDES), choices=list(OVERRIDES))
    parser.add_argument("--lines", type=int, default=1_000_000, help="table: lines streamed")
    parser.add_argument("--windows", type=int, default=100_000, help="recordings: windows predicted")
    parser.add_argument("--frames", type=int, default=1_000_000, help="tracker: frames streamed")
    parser.add_argument("--hop", type=int, default=4, help="recordings: steps between windows")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2],
                        help="one soak per seed: the model is trained with it (the stream is its scene's readings)")
    parser.add_argument("--plot-kind", default="table", help=f"the kind whose live view is drawn to {FIGURE}")
    args = parser.parse_args(argv)
    with recording("soak_stream", MEASURED_CODE) as record, tempfile.TemporaryDirectory() as tmp:
        for kind in args.kinds:
            runs = []
            for seed in args.seeds:
                folder = Path(tmp) / f"{kind}_{seed}"
                folder.mkdir()
                model, readings, extra, rest = train(kind, seed, folder / "run")
                window = OnnxPredictor(model).window_steps if kind == "recordings" else 1
                hop = args.hop if kind == "recordings" else None
                n_lines = {"table": args.lines, "recordings": window + (args.windows - 1) * args.hop,
                           "tracker": args.frames}[kind]
                write_lines(folder / "stream.csv", readings, n_lines, rest)
                print(f"{kind}, seed {seed}: streaming {n_lines:,} lines through predict.py", file=sys.stderr,
                      flush=True)
                figures = soak(model, folder / "stream.csv", extra, folder, hop)
                expected = expected_predictions(kind, n_lines, window, hop or 1, rest)
                figures.update(seed=seed, lines_in=n_lines, expected_predictions=expected,
                               lost=expected - figures["distinct_lines"], window_steps=window, hop=hop)
                runs.append(figures)
                if kind == args.plot_kind and seed == args.seeds[0]:
                    draw_live_view(model, folder / "stream.csv", extra, FIGURE)
                print(f"{kind}, seed {seed}: {n_lines:,} lines, {figures['predictions']:,} predictions "
                      f"({figures['lost']} lost, {figures['duplicated']} duplicated); RSS "
                      f"{figures['rss_after_warmup_mb']:.1f} -> {figures['rss_end_mb']:.1f} MB; p50 "
                      f"{figures['p50_first_us']:.0f} -> {figures['p50_last_us']:.0f} µs, p99 "
                      f"{figures['p99_first_us']:.0f} -> {figures['p99_last_us']:.0f} µs; loop overhead "
                      f"{figures['overhead_us']:.1f} µs wall, {figures['overhead_cpu_us']:.1f} µs CPU per prediction; "
                      f"threads {figures['most_threads']}", flush=True)
            record.add(kind, {"kind": kind, "overrides": OVERRIDES[kind], "runs": runs}, seeds=list(args.seeds))

if __name__ == "__main__":
    main()
