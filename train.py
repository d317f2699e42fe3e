"""Train and evaluate one Touchstone model: `python train.py model=resmlp scene.n_samples=2000 seed=3`.

Thin on purpose: Hydra composes the config, models/runs/run.py does the work, export/ writes the
ONNX file, and a user-input problem ends in one line on stderr and exit code 2 instead of a
traceback.
"""
import logging
import os
import shutil
import sys
from pathlib import Path

# Nothing is installed into site-packages (no top-level `data`, `models`, `export` packages to
# shadow a user's own): the repo root is the import root. Jobs that a launcher starts in other
# processes (submitit, joblib) inherit it through PYTHONPATH.
ROOT = Path(__file__).resolve().parent
STAGE = ".staging"
log = logging.getLogger("train")
os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))

import hydra
from hydra import compose, initialize_config_dir
from hydra.core.hydra_config import HydraConfig
from hydra.types import RunMode
from omegaconf import DictConfig

from data.atomic import atomic_write_text
from data.errors import InputError
from export.latency import record_costs
from export.run_export import export_run
from models.runs.run import run


@hydra.main(version_base="1.3", config_path="configs", config_name="config")
def main(cfg: DictConfig) -> float:
    output_dir = Path(HydraConfig.get().runtime.output_dir)
    # Stage every artefact in a hidden folder and move it into place only when the whole run
    # (training, report, export, cost) succeeded: a failed run leaves its log, its .hydra/ and
    # error.txt, never a metrics.json or a model that looks finished.
    stage = output_dir / STAGE
    shutil.rmtree(stage, ignore_errors=True)
    try:
        metrics = run(cfg, stage)
        if cfg.export.enabled:
            export_run(stage, cfg.export.opset, cfg.export.file)
        if cfg.cost.measure_latency:
            metrics = record_costs(stage, cfg.export.file, cfg.cost.budget_s)
        for item in sorted(stage.iterdir()):
            os.replace(item, output_dir / item.name)
        stage.rmdir()
        log.info("outputs in %s", output_dir)
    except BaseException as error:
        shutil.rmtree(stage, ignore_errors=True)
        message = str(error).splitlines()[0] if str(error) else type(error).__name__
        atomic_write_text(output_dir / "error.txt", f"{message}\n")
        if not isinstance(error, InputError):
            raise
        print(f"error: {error}", file=sys.stderr)
        if HydraConfig.get().mode == RunMode.MULTIRUN:  # one bad job must not end the sweep
            return float("nan")
        sys.exit(2)
    val = metrics.get("val", {})  # the value a Hydra sweeper would optimise: validation, never test
    if "average" in val:
        return val["average"]["r2"]
    return val.get("accuracy", float("nan"))


def check_overrides(argv: list[str]) -> None:
    """Compose the config once up front so that an unknown option or key, or a malformed
    override, is one line and exit code 2 like every other input error (Hydra would print a
    multi-line message and exit 1). Sweeps and Hydra's own flags are left to Hydra."""
    if any(arg.startswith("-") for arg in argv):
        return
    try:
        with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
            compose(config_name="config", overrides=argv, return_hydra_config=True)
    except Exception as error:  # Hydra's and OmegaConf's composition errors
        message = " ".join(str(error).split("Config search path")[0].split())
        print(f"error: {message}", file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    check_overrides(sys.argv[1:])
    main()
