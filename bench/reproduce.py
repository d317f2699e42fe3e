"""Does a fresh checkout reproduce the committed record of the default run? Re-runs
`python train.py seed=<s>` and prints its choice and scores beside the record's (results/quick_tour.jsonl),
every digit the run prints; exit 1 on any difference. The outcome is recorded (results/reproduce.jsonl).

    .venv/bin/python bench/reproduce.py            # seed 0
    .venv/bin/python bench/reproduce.py --seed 1
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


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    record = latest("quick_tour", "default")
    index = record["seeds"].index(args.seed)
    recorded = {"metrics": record["values"]["metrics_by_seed"][index],
                "choice": latest("quick_tour", "default_scores")["values"]["by_seed"][index]}
    with tempfile.TemporaryDirectory() as folder:
        done = subprocess.run([sys.executable, "train.py", f"seed={args.seed}", f"hydra.run.dir={folder}"], cwd=ROOT,
                              env={**os.environ, "CI": "true"}, capture_output=True, text=True)
        if done.returncode != 0:
            raise SystemExit(f"reproduce: train.py exited {done.returncode}: {done.stderr.strip().splitlines()[-1:]}")
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
    print("\n".join(found) if found else "reproduced: every printed digit identical")
    with recording("reproduce", MEASURED_CODE) as result:
        result.add("default_run", {"reproduced": not found, "differences": found,
                                   "recorded_commit": record["commit"]}, seeds=[args.seed])
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
