"""Every sweep ends in a report of what accuracy costs: pareto.csv, pareto.md, pareto.png and
jobs.csv (one row per job).

A Hydra callback (`on_multirun_end`, registered in configs/hydra/default.yaml) reads every
job's metrics.json in the sweep folder; by hand: `python -m runs.report.pareto <sweep dir>`. A
hyper-parameter search reports its whole study instead, whichever worker ran each trial: its
sweeper passes the trials' job folders (hydra_plugins/touchstone_optuna_sweeper/study_report.py).

Choose on validation, report on test: the score that ranks configurations and marks the front
is the VALIDATION score (R^2 averaged over targets for regression, accuracy for
classification); the test score sits in its own column for reporting only. Jobs that differ
only in `seed` are one configuration: the report shows mean ± standard deviation over its
seeds and computes the front on the means (sweep `seed=0,1,2` beside the other axes). Costs are
the fit time and the batch-1 inference latency (onnxruntime when the job exported, else eager).
A configuration is Pareto-optimal when no other is at least as accurate and at least as cheap,
and strictly better in one. Only jobs whose status.json says finished (common/run_status.py) are
results; the others (failed, interrupted, still running) are listed with their state and
reason, never dropped.
"""
import json
import logging
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import yaml
from hydra.experimental.callback import Callback

from common.atomic import atomic_write, atomic_write_text
from common.run_status import run_status
from common.spread import format_mean_and_sd

log = logging.getLogger(__name__)

MEASURES = ("val_score", "test_score", "fit_time_s", "latency_p50_us", "model_size_bytes")


def _job_row(name: str, folder: Path) -> dict:
    overrides_file = folder / ".hydra" / "overrides.yaml"
    if not overrides_file.is_file():  # a study's trial run on another machine's disk, or not begun
        return {"job": name, "folder": str(folder), "overrides": [], "status": "missing",
                "error": f"{folder}: no job folder here"}
    overrides = yaml.safe_load(overrides_file.read_text()) or []
    status = run_status(folder)
    if status.state != "finished":  # failed, interrupted, still running: its files, if any, are not a result
        return {"job": name, "folder": str(folder), "overrides": overrides, "status": status.state,
                "error": status.reason}
    row = {"job": name, "folder": str(folder), "overrides": overrides, "status": "ok"}
    metrics = json.loads((folder / "metrics.json").read_text())
    regression = "r2" in metrics["val"].get("average", {})
    score = (lambda split: split["average"]["r2"]) if regression else (lambda split: split["accuracy"])
    row["score_metric"] = "R² (mean over targets)" if regression else "accuracy"
    row["val_score"] = score(metrics["val"])
    row["test_score"] = score(metrics["test"]) if "test" in metrics else np.nan
    cost = metrics.get("cost", {})
    row["fit_time_s"] = cost.get("fit_time_s", metrics.get("fit_time_s"))
    row["fit_cpu_time_s"] = cost.get("fit_cpu_time_s")
    latency = cost.get("latency_batch1_us", {})
    onnx = [latency[k]["p50"] for k in ("onnx_1_thread", "onnx_default") if k in latency]
    row["latency_p50_us"] = min(onnx) if onnx else latency.get("eager", {}).get("p50", np.nan)
    row["latency_source"] = "onnxruntime" if onnx else ("eager" if latency else None)
    row["eager_latency_p50_us"] = latency.get("eager", {}).get("p50")
    row["model_size_bytes"] = cost.get("model_size_bytes", np.nan)
    row["n_parameters"] = cost.get("n_parameters", cost.get("n_nodes"))
    over_splits = metrics.get("spread", {}).get("test", {}).get("average", {}).get("r2")
    if over_splits is not None:   # a regression job scored over repeated splits (spread.splits)
        row["test_splits_mean"], row["test_splits_sd"] = over_splits["mean"], over_splits["sd"]
        row["n_splits"] = over_splits["n"]
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


def _settings(overrides) -> dict:
    return dict(o.split("=", 1) for o in overrides if "=" in o)


def _labels(pairs: list[dict]) -> list[str]:
    """The overrides (seed aside) that differ between jobs, so each point says what distinguishes it."""
    keys = sorted({k for p in pairs for k in p})
    varying = [k for k in keys if len({p.get(k) for p in pairs}) > 1]

    def short(key):  # model.n_estimators -> n_estimators; +experiment/accuracy_vs_time -> accuracy_vs_time
        return key.lstrip("+~").split(".")[-1].split("/")[-1]

    def value(text):  # a search's trials differ in long floats: 4 significant digits tell them apart
        try:
            number = float(text)
        except ValueError:
            return text
        return text if number.is_integer() else f"{number:.4g}"

    def label(p, shorten):
        return " ".join(f"{short(k)}={value(p[k]) if shorten else p[k]}" for k in varying if k in p) or "(all jobs alike)"

    full, rounded = [label(p, False) for p in pairs], [label(p, True) for p in pairs]
    # jobs alike but for the seed are grouped by label: rounding must never merge two configurations
    return rounded if len(set(rounded)) == len(set(full)) else full


def sweep_jobs(sweep_dir) -> dict[str, Path]:
    """The job folders of one sweep, by name (its job numbers), in order."""
    folders = sorted((f for f in Path(sweep_dir).iterdir() if (f / ".hydra" / "overrides.yaml").is_file()),
                     key=lambda f: (len(f.name), f.name))
    return {f.name: f for f in folders}


def collect_jobs(sweep_dir) -> pd.DataFrame:
    """One row per job folder of the sweep."""
    return job_table(sweep_jobs(sweep_dir))


def job_table(jobs: dict[str, Path]) -> pd.DataFrame:
    """One row per job (name -> folder)."""
    rows = [_job_row(name, Path(folder)) for name, folder in jobs.items()]
    frame = pd.DataFrame(rows)
    if frame.empty:
        return frame
    settings = [_settings(r["overrides"]) for r in rows]
    frame["seed"] = [s.get("seed", "") for s in settings]
    frame["label"] = _labels([{k: v for k, v in s.items() if k != "seed"} for s in settings])
    frame["overrides"] = frame["overrides"].map(" ".join)
    for column in MEASURES:
        if column not in frame:
            frame[column] = np.nan
    return frame


def summarise(jobs: pd.DataFrame) -> pd.DataFrame:
    """One row per configuration (jobs alike but for the seed): mean and sd over its seeds, the
    Pareto fronts on the means of the validation score, ranked by the validation score."""
    ok = jobs[jobs["status"] == "ok"]
    rows = []
    for label, group in ok.groupby("label", sort=False):
        row = {"label": label, "n_seeds": len(group), "jobs": " ".join(group["job"]),
               "score_metric": group["score_metric"].iloc[0]}
        for column in MEASURES:
            values = pd.to_numeric(group[column], errors="coerce")
            row[f"{column}_mean"] = values.mean()
            row[f"{column}_sd"] = values.std(ddof=1) if len(values) > 1 else np.nan
        if "test_splits_mean" in group:   # over each job's splits: the mean of means, the sds pooled
            row["test_splits_mean"] = pd.to_numeric(group["test_splits_mean"], errors="coerce").mean()
            row["test_splits_sd"] = np.sqrt((pd.to_numeric(group["test_splits_sd"], errors="coerce") ** 2).mean())
            row["n_splits"] = pd.to_numeric(group["n_splits"], errors="coerce").max()
        rows.append(row)
    frame = pd.DataFrame(rows)
    if frame.empty:
        return frame
    frame["pareto_fit_time"] = pareto_mask(frame["val_score_mean"], frame["fit_time_s_mean"])
    frame["pareto_latency"] = pareto_mask(frame["val_score_mean"], frame["latency_p50_us_mean"])
    return frame.sort_values("val_score_mean", ascending=False, na_position="last").reset_index(drop=True)


def markdown(summary: pd.DataFrame, jobs: pd.DataFrame, parallel_warning: bool, note: str = "") -> str:
    metric = summary["score_metric"].iloc[0] if len(summary) else "score"
    lines = [f"# Accuracy vs cost: validation {metric} ranks and marks the front; test is for reporting only", ""]
    if note:
        lines += [f"> {note}", ""]
    if parallel_warning:
        lines += ["> Jobs ran in parallel: they competed for the cores, so fit times and latencies are",
                  "> perturbed. Rerun the sweep with the basic launcher to compare timings.", ""]
    splits = "test_splits_mean" in summary and np.isfinite(summary["test_splits_mean"].astype(float)).any()
    lines += ["Mean ± sd over each configuration's seeds" + (
              "; test over splits: each job refitted on repeated splits of its data (spread.splits), "
              "the mean of the jobs' means ± their pooled sd." if splits else "."), "",
              "| configuration | seeds | validation | test (reporting only) | "
              + ("test over splits | " if splits else "") + "fit time (s) | latency p50 (µs) "
              "| size (MB) | Pareto: fit | Pareto: latency |",
              "|---|---|---|---|---|---|---|---|---|" + ("---|" if splits else "")]
    for _, r in summary.iterrows():
        size = f"{r['model_size_bytes_mean'] / 1e6:.1f}" if np.isfinite(r["model_size_bytes_mean"]) else "—"
        over_splits = ""
        if splits:
            over_splits = (f"{format_mean_and_sd(r['test_splits_mean'], r['test_splits_sd'], '.4f')} "
                           f"({int(r['n_splits'])} splits) | " if np.isfinite(r["test_splits_mean"]) else "— | ")
        # over the seeds; one seed has no sd (the mean alone), a cost never measured reads —
        val, test, fit_time, latency = (
            format_mean_and_sd(r[f"{column}_mean"], r[f"{column}_sd"], spec, missing="—")
            for column, spec in (("val_score", ".4f"), ("test_score", ".4f"), ("fit_time_s", ".2f"),
                                 ("latency_p50_us", ",.0f")))
        lines.append(f"| {r['label']} | {r['n_seeds']} | {val} | {test} | {over_splits}{fit_time} | {latency} | {size} "
                     f"| {'★' if r['pareto_fit_time'] else ''} | {'★' if r['pareto_latency'] else ''} |")
    failed = jobs[jobs["status"] != "ok"]
    if len(failed):
        lines += ["", "Failed jobs (and any interrupted, still running or missing; not counted above):", ""]
        lines += [f"- job {r['job']} ({r['overrides']}): {r['status']}: {r['error']}" for _, r in failed.iterrows()]
    return "\n".join(lines) + "\n"


COSTS = (("fit_time_s", "pareto_fit_time", "fit time (s)"),
         ("latency_p50_us", "pareto_latency", "batch-1 latency p50 (µs)"))


def measured_costs(summary: pd.DataFrame) -> list[tuple]:
    """The costs that some configuration measured: a panel each (no latency measured: no empty panel)."""
    return [cost for cost in COSTS if np.isfinite(summary[f"{cost[0]}_mean"].astype(float)).any()]


def figure(summary: pd.DataFrame):
    from runs.report.plots import panel_grid, readable_log_axis

    metric = summary["score_metric"].iloc[0]
    costs = measured_costs(summary)
    fig, axes = panel_grid(len(costs), panel_width=6.5, panel_height=5.0)
    for ax, (cost, front, title) in zip(axes, costs):
        points = summary[np.isfinite(summary[f"{cost}_mean"].astype(float))]
        ax.errorbar(points[f"{cost}_mean"], points["val_score_mean"], yerr=points["val_score_sd"].fillna(0),
                    fmt="o", color="tab:blue", zorder=3, label="validation (mean ± sd over seeds)")
        best = points[points[front]].sort_values(f"{cost}_mean")
        ax.step(best[f"{cost}_mean"], best["val_score_mean"], where="post", color="tab:red", label="Pareto front")
        for _, r in points.iterrows():
            ax.annotate(r["label"], (r[f"{cost}_mean"], r["val_score_mean"]), fontsize=6, xytext=(3, 3),
                        textcoords="offset points")
        ax.set_xscale("log")
        readable_log_axis(ax, "x")
        ax.set(xlabel=f"{title}, log scale", ylabel=f"validation {metric} (–)",
               title=f"Validation {metric.split(' (')[0]} against {title.split(' (')[0]}")
        ax.legend(loc="lower right", fontsize=7)
    fig.tight_layout()
    return fig


def write_report(sweep_dir, jobs: dict[str, Path] | None = None, parallel: bool = False, note: str = "") -> pd.DataFrame:
    """The report of `jobs` (name -> folder; default: the sweep's own job folders) into `sweep_dir`;
    `note` heads pareto.md (a search's study still running elsewhere says so)."""
    sweep_dir = Path(sweep_dir)
    jobs = collect_jobs(sweep_dir) if jobs is None else job_table(jobs)
    if jobs.empty:
        log.warning("no jobs found in %s", sweep_dir)
        return jobs
    summary = summarise(jobs)
    atomic_write(sweep_dir / "jobs.csv", lambda tmp: jobs.to_csv(tmp, index=False))
    atomic_write(sweep_dir / "pareto.csv", lambda tmp: summary.to_csv(tmp, index=False))
    atomic_write_text(sweep_dir / "pareto.md", markdown(summary, jobs, parallel, note))
    if len(summary) and measured_costs(summary):
        fig = figure(summary)
        atomic_write(sweep_dir / "pareto.png", lambda tmp: fig.savefig(tmp, dpi=110, format="png"))
    log.info("Pareto report of %d jobs (%d not finished) in %d configurations in %s", len(jobs),
             int((jobs["status"] != "ok").sum()), len(summary), sweep_dir)
    return summary


class ParetoCallback(Callback):
    """Writes the Pareto report when a multirun ends; a hyper-parameter search has written its
    study's report itself (its trials live in several workers' sweep folders)."""

    def on_multirun_end(self, config, **kwargs) -> None:
        if "touchstone_optuna_sweeper" in str(config.hydra.sweeper.get("_target_", "")):
            return
        launcher = str(config.hydra.launcher.get("_target_", ""))
        write_report(config.hydra.sweep.dir, parallel="joblib" in launcher.lower())


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python -m runs.report.pareto <sweep dir>")
    folder = Path(sys.argv[1])
    summary = write_report(folder)
    print(markdown(summary, collect_jobs(folder), parallel_warning=False))
