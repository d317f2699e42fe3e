"""Cost records and the Pareto report of sweeps."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from runs.report.pareto import pareto_mask, summarise

ROOT = Path(__file__).resolve().parents[3]
TINY = ["scene.n_samples=120", "scene.grid_nodes=21", "scene.progress=false", "analysis.ablation=false",
        "analysis.progress=false", "cost.measure_latency=true", "cost.budget_s=0.2"]


def test_pareto_marking_on_hand_made_points():
    accuracy = [0.90, 0.95, 0.80, 0.95, np.nan, 0.70]
    cost = [1.0, 10.0, 5.0, 20.0, 0.1, 0.5]
    # 0: cheapest among the accurate; 1: most accurate at lower cost than 3; 2 is dominated by 0;
    # 3 by 1 (same accuracy, dearer); 4 has no accuracy; 5 is the cheapest of all
    assert pareto_mask(accuracy, cost).tolist() == [True, True, False, False, False, True]


def test_configurations_are_ranked_and_marked_on_validation_means_over_seeds():
    jobs = pd.DataFrame({
        "job": list("012345"), "status": ["ok"] * 6, "score_metric": ["R²"] * 6,
        "label": ["a", "a", "a", "b", "b", "b"], "seed": ["0", "1", "2"] * 2,
        # b is better on validation, a on test: the ranking and the front must follow validation
        "val_score": [0.80, 0.82, 0.84, 0.90, 0.91, 0.92], "test_score": [0.99, 0.99, 0.99, 0.50, 0.50, 0.50],
        "fit_time_s": [1.0, 1.0, 1.0, 2.0, 2.0, 2.0], "latency_p50_us": [5.0] * 6, "model_size_bytes": [1e6] * 6})
    summary = summarise(jobs)
    assert summary["label"].tolist() == ["b", "a"] and summary["n_seeds"].tolist() == [3, 3]
    assert summary["val_score_mean"].tolist() == pytest.approx([0.91, 0.82])
    assert summary["val_score_sd"].tolist() == pytest.approx([0.01, 0.02])
    # same latency: only b (more accurate on validation) is on the latency front; on fit time
    # a is cheaper, so both are
    assert summary["pareto_latency"].tolist() == [True, False]
    assert summary["pareto_fit_time"].tolist() == [True, True]


def sweep(tmp_path, *overrides):
    result = subprocess.run([sys.executable, str(ROOT / "train.py"), "-m", *TINY, *overrides,
                             f"hydra.sweep.dir={tmp_path / 'sweep'}"], capture_output=True, text=True, cwd=tmp_path,
                            timeout=600)
    assert result.returncode == 0, result.stderr[-2000:]
    return tmp_path / "sweep"


def test_a_two_job_sweep_ends_in_a_report_with_both_jobs_and_their_costs(tmp_path):
    folder = sweep(tmp_path, "model=decision_tree,extra_trees")
    for name in ("pareto.csv", "pareto.md", "pareto.png"):
        assert (folder / name).stat().st_size > 0
    report, jobs = pd.read_csv(folder / "pareto.csv"), pd.read_csv(folder / "jobs.csv")
    assert sorted(report["label"]) == ["model=decision_tree", "model=extra_trees"]
    assert (jobs["status"] == "ok").all() and report["pareto_latency"].any()
    assert report["val_score_mean"].is_monotonic_decreasing and report["test_score_mean"].notna().all()
    for job in ("0", "1"):
        cost = json.loads((folder / job / "metrics.json").read_text())["cost"]
        assert cost["fit_time_s"] > 0 and cost["fit_cpu_time_s"] > 0 and cost["n_nodes"] > 0
        assert cost["model_size_bytes"] > 0 and cost["cores"] >= 1
        for runner in ("eager", "onnx_1_thread", "onnx_default"):
            assert cost["latency_batch1_us"][runner]["p50"] > 0 and cost["throughput_batch1024_per_s"][runner] > 0
    assert "★" in (folder / "pareto.md").read_text()


def test_a_failed_job_is_listed_as_failed(tmp_path):
    folder = sweep(tmp_path, "model=decision_tree", "scene.n_samples=-5,120")
    report = pd.read_csv(folder / "jobs.csv")
    failed = report[report["status"] == "failed"]
    assert len(failed) == 1 and "n_samples must be a positive integer" in failed["error"].iloc[0]
    assert "Failed jobs" in (folder / "pareto.md").read_text()
    by_hand = subprocess.run([sys.executable, "-m", "runs.report.pareto", str(folder)], capture_output=True, text=True,
                             cwd=ROOT)
    assert by_hand.returncode == 0 and "Failed jobs" in by_hand.stdout


def test_submitit_local_runs_the_same_code_path(tmp_path):
    folder = sweep(tmp_path, "hydra/launcher=submitit_local", "hydra.launcher.timeout_min=10",
                   "model=decision_tree", "seed=0,1")
    report, jobs = pd.read_csv(folder / "pareto.csv"), pd.read_csv(folder / "jobs.csv")
    assert len(jobs) == 2 and (jobs["status"] == "ok").all()
    assert report["n_seeds"].tolist() == [2] and np.isfinite(report["val_score_sd"]).all()
