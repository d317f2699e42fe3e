"""Does a fresh checkout reproduce the committed records? Re-runs the default run (`python train.py
seed=<s>`) and prints its choice and scores beside the record's (results/quick_tour.jsonl), every
digit the run prints; with --recordings, also one recordings run on a public set (`python train.py
data=recordings_npz data.path=<set>.npz model=minirocket seed=<s> threads=1`, the set exported from
aeon's wheel as bench/tsc_peers.py does) against results/tsc_peers.jsonl. Exit 1 on any
difference. The outcome is recorded (results/reproduce.jsonl).

    .venv/bin/python bench/reproduce.py                          # the default run, seed 0
    .venv/bin/python bench/reproduce.py --recordings GunPoint    # and MiniRocket on GunPoint
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from common.result_records import differences, latest, recording  # noqa: E402

MEASURED_CODE = ["common/", "data/", "models/", "export/", "runs/", "configs/", "train.py"]
PEER_PYTHON = ROOT / "bench" / ".venv-aeon" / "bin" / "python"


def recordings_run(name: str, seed: int) -> list[str] | None:
    """MiniRocket on one of aeon's sets against its tsc_peers record: the differences, or None
    (one line said) when aeon's venv, which holds the set, is not there."""
    if not PEER_PYTHON.exists():
        print(f"recordings skipped: {PEER_PYTHON.relative_to(ROOT)} is missing (python bench/tsc_peers.py --quick creates it)")
        return None
    record = latest("tsc_peers", f"{name}/minirocket")
    recorded = record["values"]["accuracy"][record["seeds"].index(seed)]
    with tempfile.TemporaryDirectory() as folder:
        subprocess.run([str(PEER_PYTHON), "bench/tsc_peers_aeon.py", "export", folder, name], cwd=ROOT, check=True,
                       stdout=subprocess.DEVNULL)
        run(["data=recordings_npz", f"data.path={folder}/{name}.npz", "model=minirocket", f"seed={seed}", "threads=1",
             f"hydra.run.dir={folder}/run"])
        fresh = json.loads((Path(folder) / "run" / "metrics.json").read_text())["test"]["accuracy"]
    print(f"{name} minirocket test accuracy: {recorded:.4f} | {fresh:.4f}")
    return differences({"accuracy": recorded}, {"accuracy": fresh})


def run(overrides: list[str]) -> None:
    done = subprocess.run([sys.executable, "train.py", *overrides], cwd=ROOT, env={**os.environ, "CI": "true"},
                          capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"reproduce: train.py exited {done.returncode}: {done.stderr.strip().splitlines()[-1:]}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--recordings", metavar="SET", help="also MiniRocket on this set (e.g. GunPoint)")
    args = parser.parse_args(argv)
    record = latest("quick_tour", "default")
    index = record["seeds"].index(args.seed)
    recorded = {"metrics": record["values"]["metrics_by_seed"][index],
                "choice": latest("quick_tour", "default_scores")["values"]["by_seed"][index]}
    with tempfile.TemporaryDirectory() as folder:
        run([f"seed={args.seed}", f"hydra.run.dir={folder}"])
        metrics = json.loads((Path(folder) / "metrics.json").read_text())
    fresh = {"metrics": {part: metrics[part] for part in recorded["metrics"]},
             "choice": {"chosen": metrics["choice"]["chosen"],
                        "validation_r2": {n: s["r2"] for n, s in metrics["choice"]["validation"].items()}}}
    recorded["choice"] = {key: recorded["choice"][key] for key in fresh["choice"]}
    print(f"recorded at commit {record['commit'][:9]} ({record['date']}) | this checkout")
    for target, scores in recorded["metrics"]["test"].items():
        now = fresh["metrics"]["test"][target]
        print(f"test {target}: " + ", ".join(f"{k} {v:.4f} | {now[k]:.4f}" for k, v in scores.items()))
    print(f"chosen: {recorded['choice']['chosen']} | {fresh['choice']['chosen']}; validation R²: "
          + ", ".join(f"{n} {v:.4f} | {fresh['choice']['validation_r2'][n]:.4f}"
                      for n, v in recorded["choice"]["validation_r2"].items()))
    found = differences(recorded, fresh)
    print("\n".join(found) if found else "default run reproduced: every printed digit identical")
    recordings = recordings_run(args.recordings, args.seed) if args.recordings else None
    if recordings is not None:
        print("\n".join(recordings) if recordings else f"{args.recordings} reproduced: every printed digit identical")
    with recording("reproduce", MEASURED_CODE) as result:
        result.add("default_run", {"reproduced": not found, "differences": found,
                                   "recorded_commit": record["commit"]}, seeds=[args.seed])
        if recordings is not None:
            result.add(f"recordings/{args.recordings}/minirocket", {"reproduced": not recordings,
                                                                   "differences": recordings}, seeds=[args.seed])
    return 1 if found or recordings else 0


if __name__ == "__main__":
    sys.exit(main())
