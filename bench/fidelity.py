"""Fidelity tables: what each paper observed on its sensor, measured on the scene that stands in for it.

    .venv/bin/python bench/fidelity.py --scene all --out /tmp/fidelity.md   # all five scenes, held / total
    .venv/bin/python bench/fidelity.py                    # rubber12 only (any --scene NAME)
    .venv/bin/python bench/fidelity.py --json             # the same rows as JSON
    .venv/bin/python bench/fidelity.py --scene rubber12 --config rubber12_lab --repeats 50
    .venv/bin/python bench/fidelity.py scene.measurement=opposite     # any Hydra override (one scene)
    .venv/bin/python bench/fidelity.py --patterns          # which rubber12 readout reproduces the sensitivity map
    .venv/bin/python bench/fidelity.py --scene fingertip              # + Algorithm 1's diagnostic

The observations are the papers' (../shared/notes/seed-observations.md, docs/fidelity.md); one
check per observation lives in runs/fidelity/<scene>.py, which says how each is measured and
judged; a scene whose module is not there yet prints one line saying so. The scene is the
composed Hydra config `scene=<config>` (default: runs/fidelity/observations.py's CONFIGS).
"""
import argparse
import json
import os
import sys
import time
from dataclasses import asdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from common.result_records import recording  # noqa: E402
from common.spread import format_mean_sd  # noqa: E402
from common.threads import apply_threads, configured_threads  # noqa: E402
from runs.fidelity.observations import (  # noqa: E402
    SEEDS, CHECKS, CONFIGS, SCENE_MODULES, load_scene, make_probe, markdown, run_checks, scene_params,
    seeds_label)
from runs.fidelity.rubber12 import (  # noqa: E402
    SceneProbe,
    centre_widest_range,
    corners_least_sensitive,
    extra_trees_r2,
    hold_out_r2,
    mirror_ambiguity_worst_at_edges,
)
from runs.fidelity.rubber12_sizing import size_cycle_gain  # noqa: E402
from runs.fidelity.registered import registration  # noqa: E402
from runs.fidelity.fingertip import algorithm1_diagnostic, diagnostic_markdown  # noqa: E402
from data.preprocessing.features import FEATURE_GROUPS, compute_features  # noqa: E402

# rubber12 readout patterns compared by --patterns: named ones and electrode e_i against e_i+k.
PATTERNS = {"adjacent": "adjacent", "i vs i+3": [[i, (i + 2) % 12 + 1] for i in range(1, 13)],
            "i vs i+4": [[i, (i + 3) % 12 + 1] for i in range(1, 13)], "near_opposite (i vs i+5)": "near_opposite",
            "opposite (i vs i+6)": "opposite"}


def compare_patterns(config: str, overrides, repeats: int) -> str:
    """The sensitivity rows (4, 5), the mirror row (6) and the forest's x, y R^2 (11) for each
    readout pattern on the same scene, each as mean ± sd over the rows' seeds."""
    lines = [(f"| readout (every column: {seeds_label(SEEDS)}, mean ± sd) | channels | "
              "sensitivity per mm: corners / edge mid / centre (row 4) | P5 span / best span (row 5) | "
              "mirror ambiguity edge / centre (row 6) | R² x, y (row 11) | "
              f"R² x / y / depth, random presses ({RANDOM_PRESSES}) |"),
             "|---|---|---|---|---|---|---|"]
    params = scene_params(config, overrides)
    for name, pattern in PATTERNS.items():
        probe = SceneProbe({**params, "measurement": pattern}, repeats=repeats)
        four, five = corners_least_sensitive(probe).numbers["by_seed"], centre_widest_range(probe).numbers["by_seed"]
        six = mirror_ambiguity_worst_at_edges(probe).numbers["by_seed"]
        r2 = np.array(extra_trees_r2(probe).numbers["by_seed"])
        sensitivity = " / ".join(format_mean_sd(100 * np.array(four[k])) for k in ("corner_mean", "edge_mean", "centre"))
        p5_share = np.array(five["range"])[:, 4] / np.max(five["range"], axis=1)
        lines.append(f"| {name} | {probe.curves[0].shape[-1]} | {sensitivity} % | {format_mean_sd(p5_share)} | "
                     f"{format_mean_sd(six['edge'], '.3f')} / {format_mean_sd(six['centre'], '.3f')} | "
                     f"{format_mean_sd(r2[:, 0], '.3f')}, {format_mean_sd(r2[:, 1], '.3f')} | "
                     f"{_random_press_r2(params, pattern)} |")
    return "\n".join(lines)


RANDOM_PRESSES = 1500


def _random_press_r2(params, pattern) -> str:
    """Row 11's forest and hold-out on uniformly drawn presses, at each seed: how well a pattern
    localises away from the lab's nine points (x, y, depth)."""
    scores = []
    for seed in SEEDS:
        probe = SceneProbe({**params, "measurement": pattern, "seed": seed})
        table = probe.scene(n_samples=RANDOM_PRESSES, protocol="random").generate()
        scores.append(hold_out_r2(compute_features(table.channels, FEATURE_GROUPS), table.targets, seed)[:3])
    return " / ".join(format_mean_sd(column, ".3f") for column in np.array(scores).T)


# What a fidelity row measures: the scenes, the checks and the models some rows train.
MEASURED_CODE = ["runs/fidelity/", "data/", "models/", "configs/scene/"]


def record_rows(record, rows, config: str):
    """One record per row: the verdict, the words it is shown in, the row's registration (the paper's
    quoted words and the statistic, runs/fidelity/registered/) and the raw numbers per seed."""
    for row in rows:
        registered = registration(row.scene, row.number)
        record.add(f"{row.scene}/{row.number}",
                   {"number": row.number, "statement": row.statement, "paper": row.paper, "config": config,
                    "value": row.measured.value, "holds": row.measured.holds, "tolerance": row.measured.tolerance,
                    "unsupported": row.measured.unsupported, "numbers": row.measured.numbers,
                    "quote": registered.quote, "statistic": registered.statistic},
                   seeds=row.measured.numbers.get("seeds", SEEDS))


def scene_section(scene: str, args, record=None) -> tuple[str, int, int, int]:
    """One scene's markdown section, and its rows held / measured / the paper supports."""
    start = time.perf_counter()
    if not load_scene(scene):
        return (f"## {scene}\n\nnot measured: {SCENE_MODULES[scene].replace('.', '/')}.py is not written yet\n",
                0, 0, 0)
    config = args.config or CONFIGS[scene]
    probe = make_probe(scene, args.overrides, args.repeats, config)
    rows = run_checks(scene, probe)
    if record is not None:
        record_rows(record, rows, config)
    supported = [row for row in rows if not row.measured.unsupported]
    held = sum(row.measured.holds is True for row in supported)
    measured = sum(row.measured.holds is not None for row in supported)
    text = (f"## {scene}\n\n`scene={config}`: {held} of {len(supported)} rows the paper supports hold ({measured} "
            f"measured; {len(rows) - len(supported)} not supported by the paper; "
            f"{time.perf_counter() - start:.0f} s)\n\n{markdown(rows)}\n")
    if scene == "fingertip":
        diagnostic = algorithm1_diagnostic(probe)
        text += (f"\n### Algorithm 1's cubic at the unseen levels (materials10, {seeds_label(diagnostic['seeds'])}, "
                 f"mean ± sd)\n\n{diagnostic_markdown(diagnostic)}\n")
    return text, held, measured, len(supported)


def size_cycle_response(args):
    """Scan rubber12's cycle_response gain_sd against the paper's repeat CV bound; print and record it."""
    probe = make_probe("rubber12", args.overrides, args.repeats, args.config)
    sized = size_cycle_gain(probe)
    for gain_sd, cv in sized["scan"].items():
        print(f"gain_sd {gain_sd:.2f}: largest lab repeat CV {format_mean_sd(100 * np.array(cv), '.2f')} % "
              f"(seeds {', '.join(f'{100 * c:.2f}' for c in cv)})")
    print(f"largest gain_sd below {100 * sized['bound']:.1f} % at every seed: {sized['gain_sd']:.2f}")
    with recording("fidelity", MEASURED_CODE) as record:
        record.add("sizing/rubber12/cycle_response", sized, seeds=list(probe.seeds))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scene", default="rubber12", choices=[*CHECKS, "all"])
    parser.add_argument("--config", default=None, help="scene config to compose (default: the scene's own)")
    parser.add_argument("--repeats", type=int, default=None,
                        help="sample size of the noise figures (rubber12: identical presses per point, 20; fingertip: "
                             "passes per level, 15; ert: two-point presses, 10); default: each scene's own")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--out", type=Path, help="also write the markdown to this file")
    parser.add_argument("--no-record", action="store_true", help="print only; append nothing to results/")
    parser.add_argument("--patterns", action="store_true", help="rubber12: compare readout patterns instead")
    parser.add_argument("--size-cycle-response", action="store_true",
                        help="rubber12: size the per-cycle response variation to the paper's repeat CV (< 2.3 %%)")
    parser.add_argument("overrides", nargs="*", help="Hydra overrides, e.g. scene.measurement=opposite")
    args = parser.parse_args(argv)
    apply_threads(configured_threads() or 1)   # as train.py's default: idle library threads cost most under load
    if args.scene == "all" and (args.config or args.overrides):
        parser.error("--config and Hydra overrides apply to one scene; pick it with --scene")

    if args.patterns:
        print(compare_patterns(args.config or "rubber12", args.overrides, args.repeats or 20))
        return
    if args.size_cycle_response:
        size_cycle_response(args)
        return
    scenes = list(CHECKS) if args.scene == "all" else [args.scene]
    if args.json:
        rows = [row for scene in scenes if load_scene(scene)
                for row in run_checks(scene, make_probe(scene, args.overrides, args.repeats, args.config))]
        print(json.dumps([asdict(row) for row in rows], indent=1, default=float))
        return
    sections, totals = [], np.zeros(3, dtype=int)
    # Rows measured on a scene's own config, with no overrides, are what docs/fidelity.md shows:
    # those are recorded (results/fidelity.jsonl); a variant run only prints.
    own = not (args.config or args.overrides or args.repeats) and not args.no_record
    with recording("fidelity", MEASURED_CODE) as record:
        for scene in scenes:
            text, *counts = scene_section(scene, args, record if own else None)
            print(text, flush=True)
            sections.append(text)
            totals += counts
    summary = (f"**{totals[0]} of {totals[2]} rows the papers support hold over {len(sections)} scene(s)** "
               f"({totals[1]} measured; load average {os.getloadavg()[0]:.2f})")
    print(summary)
    if args.out:
        args.out.write_text("\n".join(sections) + "\n" + summary + "\n")


if __name__ == "__main__":
    main()
