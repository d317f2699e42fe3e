"""The tables of measured numbers in README.md and docs/*.md, each drawn from result records.

One function per generated block, registered under the block's name; each returns the table's
markdown and the records it used (docs/generate.py writes their provenance under the table).
Numbers are formatted here and only here: the same raw values always print the same digits.
"""
from common import result_records
from common.result_records import RecordError, changed_code, latest, read_records
from common.spread import format_mean_sd

TABLES = {}


def table(name: str, provenance: bool = True):
    """Register `draw` as the block `name`; `provenance=False` for a table that is itself the
    provenance (the index of results files), so no line under it repeats it."""
    def register(draw):
        draw.provenance = provenance
        TABLES[name] = draw
        return draw
    return register


def cell(text) -> str:
    """A table cell's text: a '|' inside it (|x| for a magnitude) would end the cell."""
    return str(text).replace("|", "\\|")


def seconds(values) -> str:
    """A duration over runs: mean ± sd in seconds, or milliseconds below one second."""
    if max(values) < 1:
        return format_mean_sd([1000 * v for v in values], ".0f") + " ms"
    return format_mean_sd(values, ".1f") + " s"


def seeds_label(seeds) -> str:
    seeds = list(seeds)
    if len(seeds) > 2 and seeds == list(range(seeds[0], seeds[-1] + 1)):
        return f"seeds {seeds[0]}–{seeds[-1]}"
    return "seed " + ", ".join(map(str, seeds)) if len(seeds) == 1 else "seeds " + ", ".join(map(str, seeds))


def newest(bench: str, keep=lambda name: True) -> list[dict]:
    """The newest record of each name `keep` accepts, in the order the bench first wrote them."""
    names = dict.fromkeys(record["name"] for record in read_records(result_records.RESULTS / f"{bench}.jsonl")
                          if keep(record["name"]))
    return [latest(bench, name) for name in names]


# ---- the quick tour (bench/quick_tour.py) -------------------------------------------------------

@table("readme/tour")
def quick_tour():
    records = newest("quick_tour", lambda name: name != "default_scores")
    lines = ["| command | what it does | wall time | CPU time |", "|---|---|---|---|"]
    for record in records:
        values = record["values"]
        lines.append(f"| `{values['command']}` | {values['what']} | {seconds(values['wall_s'])} | "
                     f"{seconds(values['cpu_s'])} |")
    n = sorted({len(record["seeds"]) for record in records})
    note = (f"Mean ± sd over {', '.join(map(str, n))} runs (train commands: `seed=` each of the record's seeds), "
            "one command at a time; wall time is the whole command, CPU time user + sys.")
    return "\n".join(lines) + "\n\n" + note, records


# ---- the default run's scores (bench/quick_tour.py) ----------------------------------------------

@table("default_run/scores")
def default_run_scores():
    record = latest("quick_tour", "default_scores")
    by_seed = record["values"]["by_seed"]
    targets = [t for t in by_seed[0]["test_r2_over_splits"] if t != "average"]
    splits = by_seed[0]["n_splits"]
    lines = ["| seed | chosen on validation | validation R² of each candidate | "
             + " | ".join(f"test R² {t}" for t in targets) + " | test R² averaged over targets |",
             "|---" * (4 + len(targets)) + "|"]
    for seed, scores in zip(record["seeds"], by_seed):
        validation = ", ".join(f"{name} {r2:.4f}" for name, r2 in scores["validation_r2"].items())
        spreads = [scores["test_r2_over_splits"][t] for t in [*targets, "average"]]
        lines.append(f"| {seed} | {scores['chosen']} | {validation} | "
                     + " | ".join(f"{s['mean']:.3f} ± {s['sd']:.3f}" for s in spreads) + " |")
    averages = [scores["test_r2_over_splits"]["average"]["mean"] for scores in by_seed]
    note = (f"Each row is one `python train.py seed=<s>`; a test cell is the mean ± sd over the run's {splits} "
            f"grouped splits, the chosen model refitted on each. Across {seeds_label(record['seeds'])} the "
            f"averaged test R² is {format_mean_sd(averages, '.3f')}.")
    return "\n".join(lines) + "\n\n" + note, [record]


# ---- fidelity rows (bench/fidelity.py) -----------------------------------------------------------

FIDELITY_SCENES = ("rubber12", "fingertip", "capacitive6x6", "ert", "taxels")
VERDICT = {True: "holds", False: "does not hold", None: "not measured"}


def fidelity_verdict(row: dict) -> str:
    """A row the paper cannot support (its record names what the paper leaves out) has a verdict of its own."""
    return "not supported by the paper" if row.get("unsupported") else VERDICT[row["holds"]]


def fidelity_rows(scene: str) -> list[dict]:
    """The newest record of each of the scene's rows, in row order."""
    records = newest("fidelity", lambda name: name.startswith(f"{scene}/"))
    if not records:
        raise RecordError(f"results/fidelity.jsonl: no rows of scene {scene!r}")
    return records


def fidelity_table(scene: str):
    records = fidelity_rows(scene)
    lines = ["| # | paper's observation | paper's number | scene's measurement | tolerance | verdict |",
             "|---|---|---|---|---|---|"]
    for record in records:
        row = record["values"]
        cells = [row["number"], row["statement"], row["paper"], row["value"], row["tolerance"] or "—",
                 fidelity_verdict(row)]
        lines.append("| " + " | ".join(map(cell, cells)) + " |")
    supported = [r["values"] for r in records if not r["values"].get("unsupported")]
    held = sum(row["holds"] is True for row in supported)
    missing = [f"- **{r['values']['number']}**: {r['values']['unsupported']}" for r in records
               if r["values"].get("unsupported")]
    unsupported = ("\n\nNot supported by the paper (not counted):\n\n" + "\n".join(missing)) if missing else ""
    quoted = [f"- **{r['values']['number']}**: {r['values']['quote']} — measured as: {r['values']['statistic']}"
              for r in records if r["values"].get("quote")]
    registered = (f"\n\nThe paper's words each row is registered with (`runs/fidelity/registered/{scene}.py`), and "
                  "the statistic:\n\n" + "\n".join(quoted)) if quoted else ""
    return (f"**{held} of {len(supported)} rows the paper supports hold** (`scene={records[0]['values']['config']}`)"
            f"\n\n" + "\n".join(lines) + unsupported + registered), records


for _scene in FIDELITY_SCENES:
    table(f"fidelity/{_scene}")(lambda scene=_scene: fidelity_table(scene))


@table("fidelity/summary")
def fidelity_summary():
    lines = ["| scene | rows that hold | that do not hold | not measured | not supported by the paper |",
             "|---|---|---|---|---|"]
    used, held_all, total, unsupported_all = [], 0, 0, 0
    for scene in FIDELITY_SCENES:
        records = fidelity_rows(scene)
        used += records
        verdicts = [fidelity_verdict(r["values"]) for r in records]
        by_verdict = {v: [r["values"]["number"] for r, rv in zip(records, verdicts) if rv == v]
                      for v in (*VERDICT.values(), "not supported by the paper")}
        supported = len(records) - len(by_verdict["not supported by the paper"])
        lines.append(f"| {scene} ({len(by_verdict['holds'])} of {supported}) | "
                     + " | ".join(", ".join(numbers) or "—" for numbers in by_verdict.values()) + " |")
        held_all, total = held_all + len(by_verdict["holds"]), total + supported
        unsupported_all += len(by_verdict["not supported by the paper"])
    return (f"**{held_all} of the {total} rows the papers support hold** ({unsupported_all} rows the papers cannot "
            f"support, not counted).\n\n" + "\n".join(lines)), used


# ---- contact tracking speed (bench/contacts.py) --------------------------------------------------

@table("contacts/timing")
def contacts_timing():
    record = latest("contacts", "timing")
    values = record["values"]
    lines = ["| stream | tracker | contacts per frame | p50 per frame (µs) | p99 per frame (µs) |",
             "|---|---|---|---|---|"]
    for row in values["rows"]:
        lines.append(f"| {row['stream']} | {row['tracker']} | {row['contacts_per_frame']:.1f} | "
                     f"{format_mean_sd(row['p50_us'], '.1f')} | {format_mean_sd(row['p99_us'], '.1f')} |")
    note = (f"Scene `{values['scene']}`; mean ± sd over {len(values['rows'][0]['p50_us'])} timed runs per row "
            "(one thread, trackers alternating run by run after a warm-up run each).")
    return "\n".join(lines) + "\n\n" + note, [record]


# ---- what is recorded (every results/*.jsonl) ----------------------------------------------------

@table("results/index", provenance=False)
def results_index():
    """Each bench's newest run: when, what it cost, and whether the code it measured has moved."""
    lines = ["| results file | records | newest run | its duration | commit | state |", "|---|---|---|---|---|---|"]
    used = []
    for path in sorted(result_records.RESULTS.glob("*.jsonl")):
        records = read_records(path)
        newest = records[-1]
        run = [r for r in records if (r["date"], r["command"]) == (newest["date"], newest["command"])]
        stale = sorted({p for r in run for p in changed_code(r)})
        used += run
        lines.append(f"| `results/{path.name}` | {len(records)} | `{newest['command']}`, {newest['date'][:10]} | "
                     f"{newest['duration_s'] / 60:.1f} min | {newest['commit'][:9]}{'+dirty' if newest['dirty'] else ''} | "
                     f"{'**stale**: ' + ', '.join(stale) + ' changed' if stale else 'current'} |")
    return "\n".join(lines), used


# ---- recordings against aeon (bench/tsc_peers.py) -------------------------------------------------

def spread_or_missing(values, spec: str) -> str:
    """mean ± sd over the seeds that ran (a seed that failed is null in the record)."""
    text = format_mean_sd(values, spec, one_value="{} (one seed)", missing="failed")
    failed = sum(v is None for v in values)
    return text + (f" ({failed} failed)" if failed and text != "failed" else "")


def tsc_runs_of(command_matches) -> list[dict]:
    """The newest tsc_peers record of each name among the runs whose command matches (a later run
    of other methods on the same set does not take a table's rows away)."""
    own = {}
    for record in read_records(result_records.RESULTS / "tsc_peers.jsonl"):
        if command_matches(record["command"]) and not record["name"].startswith("quick/"):
            own[record["name"]] = record
    return list(own.values())


@table("tsc_peers/two_sets")
def tsc_peers_two_sets():
    """The bench-quick comparison: the same MiniRocket on the same official splits, ours and aeon's."""
    records = tsc_runs_of(lambda command: "tsc_peers_two_sets" in command)   # the bench-quick run's own records
    lines = ["| set | method | side | test accuracy | fit (s) | latency per recording (ms) | seeds |",
             "|---|---|---|---|---|---|---|"]
    for record in sorted(records, key=lambda r: (r["values"]["set"], r["values"]["method"])):
        values = record["values"]
        lines.append(f"| {values['set']} | `{values['method']}` | {values['side']} | "
                     f"{spread_or_missing(values['accuracy'], '.4f')} | {spread_or_missing(values['fit_s'], '.2f')} | "
                     f"{spread_or_missing(values['latency_ms'], '.2f')} | {seeds_label(record['seeds'])} |")
    note = ("Official train/test splits of the sets aeon's wheel ships; one thread; fit is the fit alone; latency is "
            "one recording at a time (Touchstone: onnxruntime p50; aeon: median of single-recording predict calls).")
    return "\n".join(lines) + "\n\n" + note, records


def _default_choices(runs: list[dict]) -> str:
    """What the default kept over its seeds, how often a costlier one was more accurate but within
    noise (the cost rule), and which candidates it did not fit."""
    kept = {}
    for run in runs:
        if run.get("chosen"):
            kept[run["chosen"]] = kept.get(run["chosen"], 0) + 1
    text = ", ".join(f"`{name}` × {count}" for name, count in kept.items())
    traded = [r["trade"] for r in runs if r.get("trade") and r["trade"]["kept"] != r["trade"]["most_accurate"]]
    if traded:
        given = sorted({round(t["accuracy_given_up"]["difference"], 3) for t in traded})
        shown = f"{given[0]:.3f}" if len(given) == 1 else f"{given[0]:.3f}–{given[-1]:.3f}"
        text += (f"; cost rule kept the cheaper on {len(traded)} of {len(runs)} (gave up {shown} held-out "
                 f"accuracy against {', '.join(sorted({t['most_accurate'] for t in traded}))})")
    skipped = {}
    for r in runs:
        for name in r.get("skipped") or []:
            skipped[name] = skipped.get(name, 0) + 1
    if skipped:
        text += "; not fitted (runs): " + ", ".join(f"{name} {count}" for name, count in skipped.items())
    fits = [r.get("fit_s") for r in runs]
    if len(runs) > 1 and None not in fits and max(fits) > 10 * min(fits):   # a mean ± sd would hide it
        text += "; fit s by seed " + ", ".join(f"{f:.1f}" for f in fits)
    return text


@table("tsc_peers/default_against_aeon")
def tsc_peers_default_against_aeon():
    """The default (no model=) and MiniRocket against aeon's MiniRocket and MultiRocket-Hydra, per
    set, with what the default kept and why (bench/tsc_peers.py runs with the default in them)."""
    records = tsc_runs_of(lambda command: " default" in command and "tsc_peers_two_sets" not in command)
    lines = ["| set | method | test accuracy | fit (s) | latency per recording (ms) | load | kept (default) |",
             "|---|---|---|---|---|---|---|"]
    for record in sorted(records, key=lambda r: (r["values"]["set"], not r["values"]["method"].startswith("aeon"),
                                                 r["values"]["method"])):
        values = record["values"]
        loads = [r["load"] for r in values["runs"] if r.get("load") is not None]
        lines.append(f"| {values['set']} | `{values['method']}` | {spread_or_missing(values['accuracy'], '.4f')} | "
                     f"{spread_or_missing(values['fit_s'], '.2f')} | {spread_or_missing(values['latency_ms'], '.2f')} | "
                     f"{min(loads):.1f}–{max(loads):.1f} | {cell(_default_choices(values['runs']))} |")
    note = ("Official train/test splits; one thread; mean ± sd over the seeds named below the table. Touchstone's "
            "fit is the whole fit (the default's: every candidate it fitted and the choosing), latency the exported "
            "graph's onnxruntime p50 at batch 1; aeon's latency the median of single-recording predict calls. Load is "
            "the 1-minute load average of the 2-core machine before each run (other work ran beside it).")
    return "\n".join(lines) + "\n\n" + note, records


AEON_ROCKET_MEMBERS = ("aeon:minirocket", "aeon:multirocket_hydra")   # aeon's ROCKET family on the bench
GOAL_METHODS = ("default", "default_most_accurate", "rocket_mixture")


def _mean(values) -> float | None:
    values = [v for v in values if v is not None]
    return sum(values) / len(values) if values else None


@table("tsc_peers/goals")
def tsc_peers_goals():
    """Issue 41's accuracy and fit-time goals per set, from the runs that measured aeon and
    Touchstone in one script run: each method's mean test accuracy against aeon's best ROCKET-family
    member's (by its mean over the same seeds), and its fit against aeon's MultiRocket-Hydra's."""
    records = tsc_runs_of(lambda command: " default" in command and "tsc_peers_two_sets" not in command)
    by = {(r["values"]["set"], r["values"]["method"]): r for r in records}
    sets = sorted({s for s, m in by if m in GOAL_METHODS})
    lines = ["| set | aeon's best member (mean accuracy) | method | mean accuracy | − best (points) | "
             "fit ÷ aeon MultiRocket-Hydra fit | same run as aeon | kept, by seed |", "|---|---|---|---|---|---|---|---|"]
    tally, used = {}, []
    for name in sets:
        members = {m: _mean(by[(name, m)]["values"]["accuracy"]) for m in AEON_ROCKET_MEMBERS if (name, m) in by}
        if not members:
            continue
        best = max(members, key=members.get)
        used += [by[(name, m)] for m in members]
        hydra = by.get((name, "aeon:multirocket_hydra"))
        for method in GOAL_METHODS:
            record = by.get((name, method))
            if record is None or _mean(record["values"]["accuracy"]) is None:
                continue
            used.append(record)
            accuracy = _mean(record["values"]["accuracy"])
            gap = 100 * (accuracy - members[best])
            ratio = (_mean(record["values"]["fit_s"]) / _mean(hydra["values"]["fit_s"])) if hydra else None
            same = all(by[(name, m)]["command"] == record["command"] for m in members)
            tally.setdefault(method, []).append((gap, ratio, same))
            lines.append(f"| {name} | `{best}` {members[best]:.4f} | `{method}` | {accuracy:.4f} | {gap:+.2f} | "
                         f"{'—' if ratio is None else f'{ratio:.1f}×'} | {'yes' if same else 'no'} | "
                         f"{', '.join(r['chosen'] for r in record['values']['runs'] if r.get('chosen')) or '—'} |")
    summary = []
    for method, rows in tally.items():
        gaps = [g for g, _, _ in rows]
        ratios = [r for _, r, _ in rows if r is not None]
        summary.append(f"`{method}`: ≥ aeon's best member on {sum(g >= 0 for g in gaps)} of {len(gaps)} sets, "
                       f"≥ best − 1 point on {sum(g >= -1 for g in gaps)} of {len(gaps)}, mean gap {_mean(gaps):+.2f} "
                       f"points; fit ≤ 3× aeon's MultiRocket-Hydra on {sum(r <= 3 for r in ratios)} of {len(ratios)}")
    note = ("Mean test accuracy over the seeds each record holds (official splits, one thread); aeon's best member "
            "is the better of its MiniRocket and MultiRocket-Hydra on that set. Goals (issue 41): ≥ best on 5 of 8 "
            "sets, ≥ best − 1 point on all, fit ≤ 3× aeon's MultiRocket-Hydra fit. " + "; ".join(summary) + ".")
    return "\n".join(lines) + "\n\n" + note, used


# ---- the default test suite's time (bench/test_suite_time.py) -----------------------------------

SUITE_CONDITIONS = {"idle": ("idle", 8), "beside_one_busy_process": ("beside one process busy on a core", 15)}


@table("readme/test_suite")
def test_suite_time():
    """Wall time of `make test` per condition, over the runs of its newest record."""
    records = newest("test_suite")
    lines = ["| machine | runs | wall time (min) | goal | tests per run: passed / failed / skipped |", "|---|---|---|---|---|"]
    for record in records:
        v = record["values"]
        words, goal_min = SUITE_CONDITIONS[record["name"]]
        runs = v["counts"] if isinstance(v["counts"], list) else [v["counts"]]   # a record of one run keeps a dict
        counts = "; ".join(f"{c.get('passed', 0):,} / {c.get('failed', 0) + c.get('error', 0)} / {c.get('skipped', 0)}"
                           for c in runs)
        lines.append(f"| {words} | {len(v['wall_s'])} | {format_mean_sd([w / 60 for w in v['wall_s']], '.2f')} | "
                     f"≤ {goal_min} | {counts} |")
    note = ("`make test` (pytest -m \"not slow\" -n 2) on this project's 2-core machine, runs one after the other; "
            "beside a busy process means beside one Python loop spinning a core for the whole run, as a user's "
            "other job would.")
    return "\n".join(lines) + "\n\n" + note, records


# ---- live streams through predict.py (bench/soak_stream.py) -------------------------------------

@table("live/soak")
def live_soak():
    """Each kind's newest soak: lines in and out, memory after warm-up and at the end, latency in
    the first and last 10 % of predictions, the loop's own cost per prediction."""
    records = [r for r in newest("soak_stream") if "runs" in r["values"]]
    lines = ["| kind | runs | lines in | predictions (expected) | lost / duplicated | memory growth after warm-up (MB) "
             "| p50 first → last 10 % (µs) | p99 first → last 10 % (µs) | p99 drift, each run | loop overhead per prediction, "
             "CPU / wall (µs) | threads | load before / after |", "|---|---|---|---|---|---|---|---|---|---|---|---|"]

    def spread(runs, key, fmt=".0f"):
        return format_mean_sd([run[key] for run in runs], fmt)

    for record in records:
        runs = record["values"]["runs"]
        for run in runs:
            run["growth_mb"] = run["rss_end_mb"] - run["rss_after_warmup_mb"]
            run["drift"] = 100 * (run["p99_last_us"] / run["p99_first_us"] - 1)
        lost = sum(run["lost"] for run in runs)
        drifts = ", ".join(f"{run['drift']:+.1f}" for run in runs)   # per run: the goal holds run by run
        duplicated = sum(run["duplicated"] for run in runs)
        lines.append(f"| {record['values']['kind']} | {len(runs)} | {runs[0]['lines_in']:,} | "
                     f"{runs[0]['predictions']:,} ({runs[0]['expected_predictions']:,}) | {lost} / {duplicated} | "
                     f"{spread(runs, 'growth_mb', '.2f')} | {spread(runs, 'p50_first_us')} → "
                     f"{spread(runs, 'p50_last_us')} | {spread(runs, 'p99_first_us')} → {spread(runs, 'p99_last_us')} "
                     f"| {drifts} % | {spread(runs, 'overhead_cpu_us', '.1f')} / "
                     f"{spread(runs, 'overhead_us', '.1f')} | {max(run['most_threads'] for run in runs)} | "
                     f"{record['load_before']:.1f} / {record['load_after']:.1f} |")
    note = ("One run per seed (the seed trains the model; the lines and predictions columns show one run's counts, "
            "lost / duplicated are summed over runs), mean ± sd over runs; "
            "`predict.py input=- backlog=wait threads=1` reading a stream "
            "generated from the scene's readings; latency per prediction is predict.py's own `latency_us` (line "
            "taken to prediction ready); loop overhead is predict.py's CPU time per prediction minus the model "
            "calls' own (onnxruntime's, or the tracker's update), and the same in wall time, which includes the "
            "time the process waited for a core on the shared machine. Threads counts the process's threads "
            "(an allocator's and onnxruntime's included); the loop itself is one. Load is the 1-minute load "
            "average of the 2-core machine before and after the whole bench: p99 moves with it.")
    return "\n".join(lines) + "\n\n" + note, records


# ---- calibration: few presses and a fitted scene (bench/calibrate.py) ----------------------------

CALIBRATE_METHODS = {"scratch": "scratch", "default_scene": "default-scene pretraining",
                     "fitted_scene": "fitted-scene pretraining", "chosen": "chosen on validation"}


@table("calibrate/learning_curves")
def calibrate_learning_curves():
    """Test mean R² per scene, N and method; the number of (draw, seed) runs under the table."""
    records = newest("calibrate", lambda name: "/N=" in name and not name.startswith("command/"))
    sizes = sorted({int(r["name"].split("=")[1]) for r in records})
    lines = ["| scene (runs) | method | " + " | ".join(f"N = {n}" for n in sizes) + " |",
             "|---" * (len(sizes) + 2) + "|"]
    scenes = list(dict.fromkeys(r["name"].split("/")[0] for r in records))
    for scene in scenes:
        mine = {int(r["name"].split("=")[1]): r["values"]["test_mean_r2"] for r in records
                if r["name"].startswith(scene + "/")}
        v = next(r["values"] for r in records if r["name"].startswith(scene + "/"))
        runs = f"{v['draws']} draws × {v['seeds_per_draw']} seed{'s' if v['seeds_per_draw'] > 1 else ''}"
        for method, words in CALIBRATE_METHODS.items():
            cells = [format_mean_sd(mine[n][method], ".3f") if n in mine else "—" for n in sizes]
            lines.append(f"| {scene} ({runs}) | {words} | " + " | ".join(cells) + " |")
    v = records[0]["values"]
    note = (f"Test R² (mean over the scene's targets) on {v['n_test']} held-out presses of a rig stand-in, mean ± sd "
            "over each scene's hidden draws and seeds"
            + ("; `--quick` settings: 1,000 simulated presses, 100 trees, 40 fit simulations" if v["quick"] else "")
            + ".")
    return "\n".join(lines) + "\n\n" + note, records


@table("calibrate/recovery")
def calibrate_recovery():
    """Per scene and parameter: how often the hidden value lay inside the fit's 95 % interval."""
    records = newest("calibrate", lambda name: name.endswith("/recovery"))
    lines = ["| scene | parameter | inside the 95 % interval | at a bound | median \\|fitted − hidden\\| / hidden "
             "| median sd / value |", "|---|---|---|---|---|---|"]
    for record in records:
        pairs = record["values"]["pairs"]
        for name in dict.fromkeys(p["parameter"] for p in pairs):
            rows = [p for p in pairs if p["parameter"] == name]
            error = sorted(abs(p["fitted"] - p["hidden"]) / abs(p["hidden"]) for p in rows)
            sd = sorted(p["sd"] / abs(p["fitted"]) for p in rows)
            lines.append(f"| {record['name'].split('/')[0]} | `{name}` | {sum(p['inside_95'] for p in rows)} of "
                         f"{len(rows)} | {sum(p['at_bound'] for p in rows)} | {error[len(error) // 2]:.1%} | "
                         f"{sd[len(sd) // 2]:.1%} |")
    inside = [p["inside_95"] for record in records for p in record["values"]["pairs"]]
    note = (f"{sum(inside)} of {len(inside)} (parameter, run) pairs inside the reported 95 % interval (1.96 sd; "
            "on the log scale for parameters fitted on one), "
            "fitted on N = 20 presses (their training part).")
    return "\n".join(lines) + "\n\n" + note, records


@table("calibrate/command")
def calibrate_command():
    """The one command's wall time per scene and table size."""
    records = newest("calibrate", lambda name: name.startswith("command/"))
    lines = ["| scene | presses in the table | wall time of the one command |", "|---|---|---|"]
    for record in records:
        v = record["values"]
        wall = seconds(v["wall_s"]) if len(v["wall_s"]) > 1 else f"{v['wall_s'][0]:.0f} s (one run)"
        lines.append(f"| {record['name'].split('/')[1]} | {v['presses']} | {wall} |")
    note = (f"`{records[0]['values']['command']}` with every default (2,000 simulated presses per scene, 200 trees), "
            f"one run each on the 2-core machine, load {records[0]['load_before']:.1f} before the first.")
    return "\n".join(lines) + "\n\n" + note, records
