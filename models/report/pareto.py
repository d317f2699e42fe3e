"""Every sweep ends in a report of what accuracy costs: pareto.csv, pareto.md and pareto.png.

A Hydra callback (`on_multirun_end`, registered in configs/hydra/default.yaml) reads every
job's metrics.json in the sweep folder; by hand: `python -m models.report.pareto <sweep dir>`.
Accuracy is the test R^2 averaged over targets (regression) or the validation accuracy
(classification); its costs are the fit time and the batch-1 inference latency (onnxruntime
when the job exported, else eager). A row is Pareto-optimal when no other job is at least as
accurate and at least as cheap, and strictly better in one. Jobs without metrics are listed
as failed, never dropped.
"""
import json
import logging
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import yaml
from hydra.experimental.callback import Callback

from data.atomic import atomic_write, atomic_write_text

log = logging.getLogger(__name__)


def _job_row(folder: Path) -> dict:
    overrides = yaml.safe_load((folder / ".hydra" / "overrides.yaml").read_text()) or []
    row = {"job": folder.name, "overrides": overrides, "status": "failed"}
    metrics_path = folder / "metrics.json"
    if not metrics_path.is_file():
        error = folder / "error.txt"
        row["error"] = error.read_text().strip() if error.is_file() else "no metrics.json (crashed or still running)"
        return row
    metrics = json.loads(metrics_path.read_text())
    val = metrics.get("val", {})
    row["status"] = "ok"
    if "average" in val:
        row["accuracy"], row["accuracy_metric"] = metrics["test"]["average"]["r2"], "test R2 (mean over targets)"
    else:
        row["accuracy"], row["accuracy_metric"] = val["accuracy"], "validation accuracy"
    cost = metrics.get("cost", {})
    row["fit_time_s"] = cost.get("fit_time_s", metrics.get("fit_time_s"))
    row["fit_cpu_time_s"] = cost.get("fit_cpu_time_s")
    latency = cost.get("latency_batch1_us", {})
    onnx = [latency[k]["p50"] for k in ("onnx_1_thread", "onnx_default") if k in latency]
    row["latency_p50_us"] = min(onnx) if onnx else latency.get("eager", {}).get("p50")
    row["latency_source"] = "onnxruntime" if onnx else ("eager" if latency else None)
    row["eager_latency_p50_us"] = latency.get("eager", {}).get("p50")
    row["model_size_bytes"] = cost.get("model_size_bytes")
    row["n_parameters"] = cost.get("n_parameters", cost.get("n_nodes"))
    return row


def pareto_mask(accuracy, cost) -> np.ndarray:
    """True where no other point is at least as accurate and as cheap, and better in one."""
    accuracy, cost = np.asarray(accuracy, dtype=float), np.asarray(cost, dtype=float)
    valid = np.isfinite(accuracy) & np.isfinite(cost)
    optimal = np.zeros(len(accuracy), dtype=bool)
    for i in np.flatnonzero(valid):
        dominated = valid & (accuracy >= accuracy[i]) & (cost <= cost[i]) & ((accuracy > accuracy[i]) | (cost < cost[i]))
        optimal[i] = not dominated.any()
    return optimal


def _labels(rows) -> list[str]:
    """The overrides that differ between jobs, so each point says what distinguishes it."""
    pairs = [dict(o.split("=", 1) for o in r["overrides"] if "=" in o) for r in rows]
    keys = sorted({k for p in pairs for k in p})
    varying = [k for k in keys if len({p.get(k) for p in pairs}) > 1]
    def short(key):
        return key.lstrip("+~").split(".")[-1]

    return [" ".join(f"{short(k)}={p[k]}" for k in varying if k in p) or r["job"] for r, p in zip(rows, pairs)]


def collect(sweep_dir) -> pd.DataFrame:
    sweep_dir = Path(sweep_dir)
    folders = sorted((f for f in sweep_dir.iterdir() if (f / ".hydra" / "overrides.yaml").is_file()),
                     key=lambda f: (len(f.name), f.name))
    rows = [_job_row(f) for f in folders]
    frame = pd.DataFrame(rows)
    if frame.empty:
        return frame
    frame["label"] = _labels(rows)
    frame["overrides"] = frame["overrides"].map(" ".join)
    for column in ("accuracy", "fit_time_s", "latency_p50_us"):
        if column not in frame:
            frame[column] = np.nan
    frame["pareto_fit_time"] = pareto_mask(frame["accuracy"], frame["fit_time_s"])
    frame["pareto_latency"] = pareto_mask(frame["accuracy"], frame["latency_p50_us"])
    return frame.sort_values("accuracy", ascending=False, na_position="last").reset_index(drop=True)


def markdown(frame: pd.DataFrame, parallel_warning: bool) -> str:
    metric = frame["accuracy_metric"].dropna().iloc[0] if frame["accuracy_metric"].notna().any() else "accuracy"
    lines = [f"# Accuracy vs cost ({metric})", ""]
    if parallel_warning:
        lines += ["> Jobs ran in parallel: they competed for the cores, so fit times and latencies are",
                  "> perturbed. Rerun the sweep with the basic launcher to compare timings.", ""]
    lines += ["| job | overrides | accuracy | fit time (s) | latency p50 (µs) | size (MB) | Pareto: fit | Pareto: latency |",
              "|---|---|---|---|---|---|---|---|"]
    for _, r in frame[frame["status"] == "ok"].iterrows():
        size = f"{r['model_size_bytes'] / 1e6:.1f}" if pd.notna(r.get("model_size_bytes")) else "—"
        latency = f"{r['latency_p50_us']:,.0f}" if pd.notna(r["latency_p50_us"]) else "—"
        lines.append(f"| {r['job']} | {r['label']} | {r['accuracy']:.4f} | {r['fit_time_s']:.2f} | {latency} | {size} "
                     f"| {'★' if r['pareto_fit_time'] else ''} | {'★' if r['pareto_latency'] else ''} |")
    failed = frame[frame["status"] != "ok"]
    if len(failed):
        lines += ["", "Failed jobs:", ""] + [f"- job {r['job']} ({r['overrides']}): {r['error']}" for _, r in failed.iterrows()]
    return "\n".join(lines) + "\n"


def figure(frame: pd.DataFrame):
    import matplotlib
    import matplotlib.ticker
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = frame[frame["status"] == "ok"]
    fig, axes = plt.subplots(1, 2, figsize=(13, 5))
    for ax, cost, front, title in ((axes[0], "fit_time_s", "pareto_fit_time", "fit time (s)"),
                                   (axes[1], "latency_p50_us", "pareto_latency", "batch-1 latency p50 (µs)")):
        points = ok[np.isfinite(ok[cost].astype(float))]
        ax.scatter(points[cost], points["accuracy"], color="tab:blue", zorder=3)
        best = points[points[front]].sort_values(cost)
        ax.step(best[cost], best["accuracy"], where="post", color="tab:red", label="Pareto front")
        for _, r in points.iterrows():
            ax.annotate(r["label"], (r[cost], r["accuracy"]), fontsize=6, xytext=(3, 3), textcoords="offset points")
        ax.set_xscale("log")
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set(xlabel=title + " (log)", ylabel="accuracy", title=f"accuracy vs {title}")
        ax.legend(loc="lower right")
    fig.tight_layout()
    return fig


def write_report(sweep_dir, parallel: bool = False) -> pd.DataFrame:
    sweep_dir = Path(sweep_dir)
    frame = collect(sweep_dir)
    if frame.empty:
        log.warning("no jobs found in %s", sweep_dir)
        return frame
    atomic_write(sweep_dir / "pareto.csv", lambda tmp: frame.to_csv(tmp, index=False))
    atomic_write_text(sweep_dir / "pareto.md", markdown(frame, parallel))
    fig = figure(frame)
    atomic_write(sweep_dir / "pareto.png", lambda tmp: fig.savefig(tmp, dpi=110, format="png"))
    log.info("Pareto report of %d jobs (%d failed) in %s", len(frame), int((frame["status"] != "ok").sum()), sweep_dir)
    return frame


class ParetoCallback(Callback):
    """Writes the Pareto report when a multirun ends."""

    def on_multirun_end(self, config, **kwargs) -> None:
        launcher = str(config.hydra.launcher.get("_target_", ""))
        write_report(config.hydra.sweep.dir, parallel="joblib" in launcher.lower())


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python -m models.report.pareto <sweep dir>")
    print(markdown(write_report(sys.argv[1]), parallel_warning=False))
