"""Study run `capacitive_tracking`: contacts with stable ids on a capacitive skin's stream (seed 001).

    python train.py experiment=capacitive_tracking                    # simulated stream, seed 0
    python train.py experiment=capacitive_tracking seed=1 scene=capacitive6x6_muca
    python train.py experiment=capacitive_tracking study.recording.path=my.csv \
        study.recording.rows=6 study.recording.cols=6 study.recording.n_rest_frames=60

Simulated (the `scene`'s stream protocol) or a user's recording (a CSV with one row-major frame
per line as the firmware streams it, or an NPY array, read by data.contact_streams.load_frames;
a data config whose _target_ is load_frames works too). Every tracker listed under `trackers`
(ours and the paper's algorithm by default) is fitted on the rest frames and run frame by frame;
with ground truth each is evaluated (models/report/tracking_metrics.py). Writes metrics.json,
contacts.csv (the first tracker's contacts: frame, id, x_mm, y_mm, cells, mean_load, peak_load,
force_n) and contacts_<name>.csv for the others, TensorBoard scalars, contacts.gif (heatmap with
ids, a time-series panel per contact, as the paper's Fig. 13-14) and contacts.png (one frame).

Force per contact: with `force_model: linear` on a simulated stream, a least-squares line from a
contact's load sum (RMC counts above rest and above threshold, 3 x 3 cells around its peak) to
force, fitted on the same scene's characterisation presses at cell centres processed with each
tracker's own thresholds (the paper's "correlation factor" is the slope of such a fit on one
cell's reading, sec. 3.5; a moving touch shares its load between up to four crossings, so the
sum around the peak is the steadier feature).
"""
import time
from pathlib import Path

import numpy as np
import pandas as pd
from hydra.utils import get_object, instantiate
from omegaconf import DictConfig, OmegaConf
from sklearn.linear_model import LinearRegression

from data.atomic import atomic_write_json, atomic_write_text
from data.contact_streams import ContactStream, load_frames
from data.errors import InputError
from models.contact_tracker import ContactTracker
from models.report.contact_animation import write_contact_animation
from models.report.tensorboard_logger import TensorBoardLogger
from models.report.tracking_metrics import evaluate_tracking

CSV_COLUMNS = ["frame", "id", "x_mm", "y_mm", "cells", "mean_load", "peak_load", "force_n"]


def load_stream(cfg: DictConfig, recording: dict | None) -> tuple[ContactStream, object]:
    """The stream to track and the scene that made it (None for a recording)."""
    if recording and recording.get("path"):
        return load_frames(**recording), None
    data = cfg.get("data")
    if data is not None and data.get("_target_") and get_object(data._target_) is load_frames:
        return instantiate(data), None
    if cfg.get("scene") is None:
        raise InputError("capacitive_tracking: no recording path and no scene to simulate a stream")
    scene = instantiate(cfg.scene)
    if not hasattr(scene, "stream"):
        raise InputError(f"capacitive_tracking: scene {cfg.scene._target_} has no stream protocol")
    return scene.stream(), scene


def characterisation_table(scene, repetitions: int):
    """The scene's robot presses at cell centres (moving-averaged change of every cell, and the
    force sensor's reading)."""
    scene.protocol = "characterisation"
    scene.n_repetitions = int(repetitions)
    return scene.generate()


def fit_force_model(table, tracker: ContactTracker) -> tuple[LinearRegression, dict]:
    """Force from what the tracker sums for a contact: the load above threshold in the 3 x 3
    cells around its peak. The same sum is taken for every characterisation press (around its
    largest cell, with the fitted tracker's thresholds) and a least-squares line is fitted to
    the force sensor's reading; slope in N per count, its inverse in counts per N (the paper's
    "correlation factor" is such a slope, sec. 3.5, there on one cell's reading)."""
    reading = table.channels
    peak_cell = reading.argmax(axis=1)
    window = tracker.neighbourhood_[peak_cell]
    above = reading > (tracker.threshold_ - tracker.mean_)
    summed = (np.take_along_axis(reading * above, window, axis=1) * tracker.window_weight_[peak_cell]).sum(axis=1)
    force = table.frame["force_n"].to_numpy(float)
    model = LinearRegression().fit(summed[:, None], force)
    slope = float(model.coef_[0])
    return model, {"kind": "linear on the 3x3 load sum above threshold", "presses": int(len(force)),
                   "n_per_count": slope, "counts_per_n": float(1.0 / slope) if slope else float("nan"),
                   "intercept_n": float(model.intercept_), "r2_fit": float(model.score(summed[:, None], force))}


def track(stream: ContactStream, params: dict, force_table, keep_images: bool):
    """Fit on the rest frames (and the force line, given presses), update frame by frame;
    returns (contacts with stream frame numbers, timing, force-model summary, images)."""
    tracker = ContactTracker(rows=stream.rows, cols=stream.cols, pitch_mm=stream.pitch_mm, **params)
    tracker.fit(stream.frames[:stream.n_rest_frames])
    force_info = None
    if force_table is not None:
        model, force_info = fit_force_model(force_table, tracker)
        tracker.set_params(force_model=model, force_feature="sum")  # read from the first update on
    live = stream.frames[stream.n_rest_frames:]
    records, elapsed_ns = [], np.zeros(len(live))
    labels = np.zeros(live.shape, dtype=np.int64) if keep_images else None
    clock = time.perf_counter_ns
    for index, frame in enumerate(live):
        start = clock()
        contacts = tracker.update(frame)
        elapsed_ns[index] = clock() - start
        if len(contacts):
            records.extend(contacts.records())
            if keep_images:
                labels[index] = contacts.labels
    table = pd.DataFrame(records, columns=["frame", "id", "x_mm", "y_mm", "cells", "area_mm2", "mean_load",
                                           "peak_load", "force_n"])
    table["frame"] += stream.n_rest_frames
    timing = {"p50_us": float(np.percentile(elapsed_ns, 50) / 1e3) if len(live) else float("nan"),
              "p99_us": float(np.percentile(elapsed_ns, 99) / 1e3) if len(live) else float("nan"),
              "frames": int(len(live)),
              "note": "inside the study run, beside other work: bench/contacts.py measures speed"}
    images = None
    if keep_images:
        grid = (stream.rows, stream.cols)
        load = live - tracker.mean_.reshape(grid)
        images = (labels, load > (tracker.threshold_ - tracker.mean_).reshape(grid), load)
    return table, timing, force_info, images


def run_capacitive_tracking(cfg: DictConfig, output_dir, trackers: dict, min_force_n: float = 0.3,
                            match_radius_mm: float | None = None, force_model: str | None = "linear",
                            force_repetitions: int = 10, recording: dict | None = None,
                            animation: dict | None = None) -> dict:
    output_dir = Path(output_dir)
    output_dir.mkdir(parents=True, exist_ok=True)
    trackers = OmegaConf.to_container(trackers, resolve=True) if isinstance(trackers, DictConfig) else dict(trackers)
    recording = OmegaConf.to_container(recording, resolve=True) if isinstance(recording, DictConfig) else recording
    animation = dict(animation or {})
    if not trackers:
        raise InputError("capacitive_tracking: study.trackers lists no tracker")
    if force_model not in (None, "none", "linear"):
        raise InputError(f"capacitive_tracking: force_model must be linear or none, got '{force_model}'")
    stream, scene = load_stream(cfg, recording)
    radius = float(match_radius_mm) if match_radius_mm is not None else stream.pitch_mm
    force_table = characterisation_table(scene, force_repetitions) if force_model == "linear" and scene is not None else None
    metrics = {"stream": {"source": stream.description.get("source", "scene"), "frames": stream.n_frames,
                          "rest_frames": stream.n_rest_frames, "grid": [stream.rows, stream.cols],
                          "pitch_mm": stream.pitch_mm, "frame_rate_hz": stream.frame_rate_hz,
                          "ground_truth": stream.truth is not None},
               "evaluation": {"match_radius_mm": radius, "min_force_n": float(min_force_n)}
               if stream.truth is not None else None,
               "trackers": {}}
    primary = next(iter(trackers))
    tables, images = {}, None
    for name, params in trackers.items():
        table, timing, force_info, frames = track(stream, dict(params or {}), force_table,
                                                  keep_images=name == primary)
        images = frames if name == primary else images
        tables[name] = table
        entry = {"params": params, "timing": timing, "force_model": force_info,
                 "contacts_reported": int(len(table)), "ids_issued": int(table.id.nunique())}
        if stream.truth is not None:
            entry.update(evaluate_tracking(stream.truth, table, stream.n_frames, radius, min_force_n,
                                           group_column="session"))
            if force_info is not None:
                entry["overall"].update(_force_error(stream.truth, table, radius))
        metrics["trackers"][name] = entry

    for name, table in tables.items():
        out = table.rename(columns={}).loc[:, CSV_COLUMNS]
        atomic_write_text(output_dir / ("contacts.csv" if name == primary else f"contacts_{name}.csv"),
                          out.to_csv(index=False, float_format="%.4f"))
    _tensorboard(output_dir, metrics, tables[primary], stream)
    labels, shown, load = images
    metrics["animation"] = write_contact_animation(
        load, shown, labels, tables[primary].assign(frame=tables[primary].frame - stream.n_rest_frames),
        output_dir / "contacts.gif", output_dir / "contacts.png", stream.pitch_mm, stream.frame_rate_hz,
        max_frames=int(animation.get("max_frames", 60)), n_panels=int(animation.get("n_panels", 3)),
        fps=int(animation.get("fps", 15)))
    atomic_write_json(output_dir / "metrics.json", _json_safe(metrics))
    return metrics


def _force_error(truth: pd.DataFrame, table: pd.DataFrame, radius: float) -> dict:
    """Force error of detections within `radius` of a true contact (nearest one per frame)."""
    merged = table.merge(truth, on="frame", suffixes=("", "_true"))
    if merged.empty:
        return {"force_rmse_n": float("nan"), "force_pairs": 0}
    merged["distance"] = np.hypot(merged.x_mm - merged.x_mm_true, merged.y_mm - merged.y_mm_true)
    near = merged[merged.distance <= radius].sort_values("distance").drop_duplicates(["frame", "id"])
    near = near.drop_duplicates(["frame", "contact_id"])
    error = near.force_n - near.force_n_true
    return {"force_rmse_n": float(np.sqrt(np.mean(error ** 2))) if len(near) else float("nan"),
            "force_mae_n": float(np.mean(np.abs(error))) if len(near) else float("nan"), "force_pairs": int(len(near))}


def _tensorboard(output_dir: Path, metrics: dict, contacts: pd.DataFrame, stream: ContactStream) -> None:
    with TensorBoardLogger(str(output_dir / "tensorboard")) as logger:
        for name, entry in metrics["trackers"].items():
            logger.writer_.add_scalar(f"timing/{name}/p50_us", entry["timing"]["p50_us"])
            for key, value in (entry.get("overall") or {}).items():
                if isinstance(value, (int, float)) and np.isfinite(value):
                    logger.writer_.add_scalar(f"tracking/{name}/{key}", value)
            for scenario, row in (entry.get("by_scenario") or {}).items():
                logger.writer_.add_scalar(f"id_switches/{name}/{scenario}", row["id_switches"])
        per_frame = contacts.groupby("frame").size().reindex(range(stream.n_frames), fill_value=0)
        for frame, count in per_frame.items():
            logger.writer_.add_scalar("stream/contacts", int(count), int(frame))


def _json_safe(value):
    if isinstance(value, dict):
        return {str(k): _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return float(value) if np.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    return value
