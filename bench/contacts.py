"""Contact tracker speed on the scene's own frames: p50 and p99 of `ContactTracker.update` per
frame, force included, one thread, timed by models/contact_tracking/timing.py (the timing the
capacitive_tracking study writes into metrics.json).

    OMP_NUM_THREADS=1 .venv/bin/python bench/contacts.py                          # the MUCA's 12 x 21 grid
    OMP_NUM_THREADS=1 .venv/bin/python bench/contacts.py --scene capacitive6x6 --runs 5

Streams, each simulated by the scene as `python train.py experiment=capacitive_tracking
scene=<scene>` simulates it (all its effects):
- sessions: the study's stream at --seed (tap, hold, glide, cross, merge and split sessions,
  1-5 contacts);
- 5 held: the scene's hold session alone at --five-seed, a seed whose hold draws 5 contacts
  (checked): 5 contacts on most frames;
- empty: the rest frames the tracker was fitted on (no contact).
Trackers: the experiment's own parameters (configs/experiment/capacitive_tracking.yaml); ours
with force (the study's default: the experiment's model fitted on the scene's characterisation
presses, read through models/contact_tracking/force.py), ours with force through the pipeline's
predict_raw (what the study did before the fold), ours without force, and the paper's algorithm
(its segmentation and tracking, no force; Egger et al. 2025 report 404.7 us per frame without contact
and 627.2 us with 5 +/- 3 contacts, 12 x 21, on its machine).

Every tracker runs on the same frames in one process, runs alternating between trackers (the
order reversed every other run) after one warm-up run each, so that a shared machine's load
falls on all of them alike; each figure is the mean +/- sd over --runs runs of that run's p50 or
p99. The load average is printed beside the numbers: on a shared machine every figure is an
upper one, p99 most of all (a process that loses the processor for a scheduler tick, 4 ms
here, makes that frame's time).
"""
import argparse
import os
import sys
from pathlib import Path

for variable in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ.setdefault(variable, "1")

import numpy as np  # noqa: E402
from hydra import compose, initialize_config_dir  # noqa: E402
from hydra.utils import instantiate  # noqa: E402
from omegaconf import OmegaConf  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import recording  # noqa: E402
from common.spread import format_mean_sd  # noqa: E402
from models.contact_tracking.force import force_reader  # noqa: E402
from models.contact_tracking.timing import latency_summary, timed_updates  # noqa: E402
from runs.studies.capacitive_tracking import fit_force_pipeline, make_tracker  # noqa: E402


def study_config(scene: str, seed: int, overrides=()):
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        return compose("config", overrides=["experiment=capacitive_tracking", f"scene={scene}", f"seed={seed}",
                                            *overrides])


def streams(scene: str, seed: int, five_seed: int) -> dict:
    """name -> (the stream, the frames to time)."""
    sessions = instantiate(study_config(scene, seed).scene).stream()
    held = instantiate(study_config(scene, five_seed, ["scene.sessions=[hold]"]).scene).stream()
    most = held.truth.groupby("frame").size().max()
    if most != 5:
        raise SystemExit(f"--five-seed {five_seed}: the hold session draws {most} contacts, not 5; pick another seed")
    rest = sessions.frames[:sessions.n_rest_frames]
    return {"sessions": (sessions, sessions.frames[sessions.n_rest_frames:]),
            "5 held": (held, held.frames[held.n_rest_frames:]),
            "empty": (sessions, rest)}


def trackers(cfg, repetitions: int) -> dict:
    """name -> (tracker parameters, force function or None)."""
    params = OmegaConf.to_container(cfg.study.trackers, resolve=True)
    pipeline, _ = fit_force_pipeline(cfg, repetitions)
    column = pipeline.target_names.index("force_n")
    return {"ours, force (folded)": (params["ours"], force_reader(pipeline)),
            "ours, force (pipeline.predict_raw)": (params["ours"], lambda w: pipeline.predict_raw(w)[0][:, column]),
            "ours, no force": (params["ours"], None),
            "paper, no force": (params["paper"], None)}


def one_run(stream, frames, params, force) -> tuple[float, float, float]:
    """p50 and p99 (us) of one run over the frames, and contacts per frame."""
    tracker = make_tracker(stream.rows, stream.cols, stream.pitch_mm, params, force)
    tracker.fit(stream.frames[:stream.n_rest_frames])
    contacts, elapsed_us = timed_updates(tracker, frames)
    summary = latency_summary(elapsed_us)
    return summary["p50_us"], summary["p99_us"], float(np.mean([len(c) for c in contacts]))


# What the timing measures: the tracker, the study that builds it, the scene that draws the frames.
MEASURED_CODE = ["models/contact_tracking/", "runs/studies/capacitive_tracking.py", "data/scenes/"]


def measure(args) -> list[dict]:
    named_streams = streams(args.scene, args.seed, args.five_seed)
    named_trackers = trackers(study_config(args.scene, args.seed), args.force_repetitions)
    print(f"scene {args.scene}; load average at start: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores\n")
    print("| stream | tracker | contacts per frame | p50 (us) | p99 (us) |")
    print("|---|---|---|---|---|")
    names, rows = list(named_trackers), []
    for stream_name, (stream, frames) in named_streams.items():
        runs = {name: [] for name in names}
        for run in range(args.runs + 1):  # run 0 warms up; then ABCD, DCBA, ABCD, ...
            for name in names if run % 2 == 0 else names[::-1]:
                figures = one_run(stream, frames, *named_trackers[name])
                if run:
                    runs[name].append(figures)
        for name in names:
            p50, p99, found = np.array(runs[name]).T
            print(f"| {stream_name} | {name} | {found[0]:.1f} | {format_mean_sd(p50, '.1f')} | "
                  f"{format_mean_sd(p99, '.1f')} |", flush=True)
            rows.append({"stream": stream_name, "tracker": name, "contacts_per_frame": found[0],
                         "p50_us": p50, "p99_us": p99})
    print(f"\n{args.runs} runs each (mean ± sd of the per-run figures); load average at end: "
          f"{os.getloadavg()[0]:.1f}")
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scene", default="capacitive6x6_muca")
    parser.add_argument("--seed", type=int, default=0, help="the sessions stream's seed")
    parser.add_argument("--five-seed", type=int, default=1, help="a seed whose hold session draws 5 contacts")
    parser.add_argument("--runs", type=int, default=5, help="timed runs per stream and tracker (>= 3 for a spread)")
    parser.add_argument("--force-repetitions", type=int, default=10, help="presses per level and cell for the force fit")
    args = parser.parse_args(argv)
    with recording("contacts", MEASURED_CODE) as record:
        rows = measure(args)
        record.add("timing", {"scene": args.scene, "rows": rows}, seeds=[args.seed, args.five_seed])


if __name__ == "__main__":
    main()
