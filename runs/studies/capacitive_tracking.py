"""Study run `capacitive_tracking`: contacts with stable ids on a capacitive skin's stream
(Egger et al. 2025).

    python train.py experiment=capacitive_tracking                    # simulated stream, seed 0
    python train.py experiment=capacitive_tracking seed=1 scene=capacitive6x6_muca
    python train.py experiment=capacitive_tracking study.recording.path=my.csv \
        study.recording.rows=6 study.recording.cols=6 study.recording.n_rest_frames=60

Simulated (the `scene`'s stream protocol) or a user's recording (a CSV with one row-major frame
per line as the firmware streams it, or an NPY array, read by data.readers.contact_streams.load_frames;
a data config whose _target_ is load_frames works too). Every tracker listed under `trackers`
(ours and the paper's algorithm by default) is fitted on the rest frames and run frame by frame;
with ground truth each is evaluated (runs/report/tracking_metrics.py). Writes metrics.json,
contacts.csv (the first tracker's contacts: frame, id, x_mm, y_mm, cells, mean_load, peak_load,
force_n) and contacts_<name>.csv for the others, TensorBoard scalars, contacts.gif (heatmap with
ids, a time-series panel per contact, as the paper's Fig. 13-14) and contacts.png (one frame).

Standard input line by line (`study.recording.path=-`, a serial stream piped in): the first
tracker prints each frame's contacts as CSV lines on standard output as the frame arrives
(frame, id, x_mm, y_mm, force_n); at the end of the input the run writes the same files as for a
recording file:
    cat /dev/ttyACM0 | python train.py experiment=capacitive_tracking study.recording.path=- \
        study.recording.rows=12 study.recording.cols=21

Force per contact comes from the regression pipeline's fitted model (`force_model: pipeline`):
the configured `model` (the experiment sets the paper's linear regression; any `model=` works)
is fitted by the shared pipeline (datamodule, grouped split, report metrics) on the scene's
characterisation presses read as the tracker reads a contact, the 3 x 3 cells around the
peak (`characterisation_channels: window`, data/preprocessing/contact_windows.py), and every tracker reads
each contact's window through that same fitted pipeline. Or `force_model: <run folder or
model.onnx>` of such a run (`python train.py experiment=capacitive_force hydra.mode=RUN
scene.characterisation_channels=window`): its exported model, run with onnxruntime (an ONNX
graph is operators and numbers; nothing in it runs as Python), or `none`.
"""
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from hydra.utils import get_object, instantiate
from omegaconf import DictConfig, OmegaConf

from common.atomic import atomic_write_text
from common.errors import InputError
from common.threads import configured_threads
from data.readers.contact_streams import ContactStream, check_grid, frames_from_lines, load_frames
from export.onnx_predictor import OnnxPredictor
from export.window_force import window_force
from models.contact_tracking import ContactTracker
from models.contact_tracking.force import force_reader
from models.contact_tracking.timing import latency_summary, timed_updates
from runs.regression import fit_and_evaluate
from runs.report.contact_animation import write_contact_animation
from runs.report.tracking_metrics import evaluate_tracking

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


def fit_force_pipeline(cfg: DictConfig, repetitions: int):
    """The configured model fitted by the regression pipeline on the scene's characterisation
    presses, each read as the 3 x 3 window around its peak, anywhere on its cell (contacts do not
    land on crossings only) -> (pipeline, summary)."""
    presses = instantiate(cfg.scene, protocol="characterisation", characterisation_channels="window",
                          n_repetitions=int(repetitions), press_offset_mm=float(cfg.scene.pitch_mm) / 2)
    datamodule = instantiate(cfg.data, source=presses).setup()
    result = fit_and_evaluate(cfg, datamodule)
    summary = {"model": result.metrics["model"], "reads": "3x3 window of loads around a contact's peak",
               "presses": int(len(datamodule.y)), "split": datamodule.summary()["split"],
               "fit_time_s": result.metrics["fit_time_s"],
               "val": result.metrics["val"], "test": result.metrics["test"]}
    return result.pipeline, summary


def load_force_model(path: str):
    """A saved run's exported model (its folder or model.onnx) that reads the 3 x 3 window to
    force_n -> (windows (n, 9) -> force_n, summary), run by onnxruntime: an ONNX graph is
    operators and numbers, nothing in it runs as Python (a pickled pipeline could)."""
    path = Path(path)
    path = path / "model.onnx" if path.is_dir() else path
    if not path.is_file():
        raise InputError(f"capacitive_tracking: force_model {path} does not exist (a run folder or its model.onnx)")
    predictor = OnnxPredictor(path, threads=configured_threads() or 1)
    read = window_force(predictor, "capacitive_tracking: force_model")
    return read, {"model": predictor.metadata.get("model", "unknown"),
                  "reads": "3x3 window of loads around a contact's peak", "loaded_from": str(path)}


def make_tracker(rows: int, cols: int, pitch_mm: float, params: dict, force) -> ContactTracker:
    """A tracker with the study's parameters, reading force with `force` (windows -> force_n) when given."""
    if force is not None:
        params = {**params, "force_model": force, "force_feature": "window"}
    return ContactTracker(rows=rows, cols=cols, pitch_mm=pitch_mm, **params)


def track_live(lines, recording: dict, params: dict, force, out) -> ContactStream:
    """Standard input line by line (a serial stream piped in): the first n_rest_frames frames fit
    the tracker, then every frame's contacts are written to `out` as CSV lines (frame, id, x_mm,
    y_mm, force_n) as it arrives. Returns every frame read, for the files written at the end."""
    rows, cols, n_rest = int(recording["rows"]), int(recording["cols"]), int(recording["n_rest_frames"])
    pitch_mm, rate_hz = float(recording["pitch_mm"]), float(recording["frame_rate_hz"])
    check_grid(rows, cols, pitch_mm, rate_hz, "stdin")
    tracker, frames = make_tracker(rows, cols, pitch_mm, params, force), []
    print("frame,id,x_mm,y_mm,force_n", file=out, flush=True)
    for frame in frames_from_lines(lines, rows, cols):
        frames.append(frame)
        if len(frames) == n_rest:
            tracker.fit(np.stack(frames))
        elif len(frames) > n_rest:
            contacts = tracker.update(frame)
            for i, x, y, f in zip(contacts.ids.tolist(), contacts.x_mm.tolist(), contacts.y_mm.tolist(),
                                  contacts.force_n.tolist()):
                print(f"{len(frames) - 1},{i},{x:.2f},{y:.2f},{f:.3f}", file=out, flush=True)
    if len(frames) < n_rest:
        raise InputError(f"stdin: {len(frames)} frames, fewer than the {n_rest} rest frames needed for a baseline")
    return ContactStream(np.stack(frames), rate_hz, pitch_mm, n_rest, None, {"source": "stdin"})


def track(stream: ContactStream, params: dict, force, keep_images: bool):
    """Fit on the rest frames, update frame by frame (force from `force`, given one);
    returns (contacts with stream frame numbers, timing, images)."""
    tracker = make_tracker(stream.rows, stream.cols, stream.pitch_mm, params, force)
    tracker.fit(stream.frames[:stream.n_rest_frames])
    live = stream.frames[stream.n_rest_frames:]
    found, elapsed_us = timed_updates(tracker, live)
    records = [record for contacts in found for record in contacts.records()]
    labels = np.array([contacts.labels for contacts in found], dtype=np.int64).reshape(live.shape) if keep_images else None
    table = pd.DataFrame(records, columns=["frame", "id", "x_mm", "y_mm", "cells", "area_mm2", "mean_load",
                                           "peak_load", "force_n"])
    table["frame"] += stream.n_rest_frames
    timing = {**latency_summary(elapsed_us),
              "note": "update per frame (force included when the run has a force model), timed as bench/contacts.py "
                      "times it, inside the run"}
    images = None
    if keep_images:
        grid = (stream.rows, stream.cols)
        load = live - tracker.mean_.reshape(grid)
        images = (labels, load > (tracker.threshold_ - tracker.mean_).reshape(grid), load)
    return table, timing, images


def run_capacitive_tracking(cfg: DictConfig, output_dir, logger, trackers: dict, min_force_n: float = 0.3,
                            match_radius_mm: float | None = None, force_model: str | None = "pipeline",
                            force_repetitions: int = 10, recording: dict | None = None,
                            animation: dict | None = None) -> dict:
    output_dir = Path(output_dir)
    output_dir.mkdir(parents=True, exist_ok=True)
    trackers = OmegaConf.to_container(trackers, resolve=True) if isinstance(trackers, DictConfig) else dict(trackers)
    recording = OmegaConf.to_container(recording, resolve=True) if isinstance(recording, DictConfig) else recording
    animation = dict(animation or {})
    if not trackers:
        raise InputError("capacitive_tracking: study.trackers lists no tracker")
    live = bool(recording) and recording.get("path") == "-"   # standard input, line by line
    stream, scene = (None, None) if live else load_stream(cfg, recording)
    force, force_info = None, None   # force: contacts' windows (n, 9) -> force_n
    if force_model == "pipeline" and scene is not None:
        pipeline, force_info = fit_force_pipeline(cfg, force_repetitions)
        force = force_reader(pipeline)
    elif force_model not in (None, "none", "pipeline"):
        force, force_info = load_force_model(force_model)
    primary = next(iter(trackers))
    if live:
        stream = track_live(sys.stdin, recording, dict(trackers[primary] or {}), force, sys.stdout)
    radius = float(match_radius_mm) if match_radius_mm is not None else stream.pitch_mm
    metrics = {"stream": {"source": stream.description.get("source", "scene"), "frames": stream.n_frames,
                          "rest_frames": stream.n_rest_frames, "grid": [stream.rows, stream.cols],
                          "pitch_mm": stream.pitch_mm, "frame_rate_hz": stream.frame_rate_hz,
                          "ground_truth": stream.truth is not None},
               "evaluation": {"match_radius_mm": radius, "min_force_n": float(min_force_n)}
               if stream.truth is not None else None,
               "force_model": force_info,
               "trackers": {}}
    tables, images = {}, None
    for name, params in trackers.items():
        table, timing, frames = track(stream, dict(params or {}), force, keep_images=name == primary)
        images = frames if name == primary else images
        tables[name] = table
        entry = {"params": params, "timing": timing,
                 "contacts_reported": int(len(table)), "ids_issued": int(table.id.nunique())}
        if stream.truth is not None:
            entry.update(evaluate_tracking(stream.truth, table, stream.n_frames, radius, min_force_n,
                                           group_column="session"))
            if force is not None:
                entry["overall"].update(_force_error(stream.truth, table, radius))
        metrics["trackers"][name] = entry

    for name, table in tables.items():
        out = table.rename(columns={}).loc[:, CSV_COLUMNS]
        atomic_write_text(output_dir / ("contacts.csv" if name == primary else f"contacts_{name}.csv"),
                          out.to_csv(index=False, float_format="%.4f"))
    _log_contacts_per_frame(logger, tables[primary], stream)
    labels, shown, load = images
    metrics["animation"] = write_contact_animation(
        load, shown, labels, tables[primary].assign(frame=tables[primary].frame - stream.n_rest_frames),
        output_dir / "contacts.gif", output_dir / "contacts.png", stream.pitch_mm, stream.frame_rate_hz,
        max_frames=int(animation.get("max_frames", 60)), n_panels=int(animation.get("n_panels", 3)),
        fps=int(animation.get("fps", 15)))
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


def _log_contacts_per_frame(logger, contacts: pd.DataFrame, stream: ContactStream) -> None:
    """The number of contacts in every frame, a TensorBoard series (the metrics' numbers are
    logged with metrics.json by runs/report/metrics_file.py)."""
    per_frame = contacts.groupby("frame").size().reindex(range(stream.n_frames), fill_value=0)
    for frame, count in per_frame.items():
        logger.writer_.add_scalar("stream/contacts", int(count), int(frame))
