"""Train and evaluate one Touchstone model: `python train.py model=resmlp scene.n_samples=2000 seed=3`.

Thin on purpose: Hydra composes the config, runs/run.py does the work, export/ writes the
ONNX file, and a user-input problem ends in one line on stderr and exit code 2 instead of a
traceback.
"""
import logging
import os
import re
import shutil
import signal
import sys
import tempfile
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
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.errors import InstantiationException
from hydra.types import RunMode
from omegaconf import DictConfig, OmegaConf

from common.distributed import export_submitit_environment, launched_rank, launched_world_size
from common.errors import InputError
from common.progress import phase
from common.run_status import config_hash, mark_failed, mark_finished, mark_running, prepare_folder
from common.threads import apply_threads, resolve_threads
from runs.config_checks import check_config
from runs.help_page import help_page
from runs.setting_hints import misspelt_setting

# torch, scikit-learn and onnx are imported in main(), after the config has been checked (a typo
# is reported in about a second) and the thread setting applied (pools start at the right size).

# Run folders are unique even for runs started in the same second: the time plus the process id
# (unique among running processes), so a folder's .hydra/ always describes the run beside it.
# Under torchrun rank 0's name is every rank's (agree_on_run_folder).
OmegaConf.register_new_resolver("process_id", os.getpid, replace=True)


@hydra.main(version_base="1.3", config_path="configs", config_name="config")
def main(cfg: DictConfig) -> float:
    output_dir = Path(HydraConfig.get().runtime.output_dir)
    # Several processes may train this run's net (torchrun, or submitit tasks: models/distributed.py);
    # they share the run folder, and rank 0 alone writes it: the others stage into a private
    # temporary folder that is deleted at the end, and log only warnings, to the console.
    export_submitit_environment()
    writer = launched_rank() == 0
    if not writer:
        quiet_logging()
    # status.json says `running` first and `finished` (or `failed`) last; a run killed outright
    # keeps `running`, which common/run_status.py reads as `interrupted` once its process is gone.
    # A scheduler's time limit (SLURM) or a plain `kill` sends SIGTERM first: end as a failed run
    # with that reason rather than vanish mid-write (SIGKILL still reads as interrupted).
    # Held back from `running` being written until the try below can record it as failed: a
    # SIGTERM in between would leave a folder that reads running (then interrupted), not failed.
    signal.signal(signal.SIGTERM, terminated)
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM})
    configuration = config_hash(cfg)
    running = mark_running(output_dir, configuration) if writer else None
    # Stage every artefact in a hidden folder and move it into place only when the whole run
    # (training, report, export, cost) succeeded: a failed run leaves its log, its .hydra/,
    # error.txt and status.json, never a metrics.json or a model that looks finished.
    stage = output_dir / STAGE if writer else Path(tempfile.mkdtemp(prefix=f"touchstone-rank{launched_rank()}-"))
    shutil.rmtree(stage, ignore_errors=True)
    moved = []
    try:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGTERM})   # one held back is raised here
        launcher = HydraConfig.get().launcher  # joblib runs n_jobs runs side by side: `all` is their share
        parallel_jobs = launcher.get("n_jobs", 1) if "joblib" in str(launcher.get("_target_", "")) else 1
        threads = resolve_threads(cfg.threads, parallel_jobs)
        apply_threads(threads)
        log.info("threads: %d per process (threads=%s)", threads, cfg.threads)
        with phase("start-up (imports)"):
            from runs.run import run
        if launched_world_size() > 1:
            from models.distributed import join_process_group
            join_process_group()
            log.info("training with %d processes; rank 0 writes the run folder", launched_world_size())
        try:  # fit, report, export, latency, metrics.json: all into the stage
            metrics = run(cfg, stage, configuration)
        except InstantiationException as error:
            raise as_input_error(error) from None
        if not writer:
            shutil.rmtree(stage)
            return run_score(metrics)
        for item in sorted(stage.iterdir()):
            os.replace(item, output_dir / item.name)
            moved.append(output_dir / item.name)
        stage.rmdir()
        mark_finished(output_dir, running)
        log.info("outputs in %s", output_dir)
    except BaseException as error:
        shutil.rmtree(stage, ignore_errors=True)
        for path in moved:  # interrupted while moving in (Ctrl-C): take back what was moved
            if path.is_dir():
                shutil.rmtree(path)
            else:
                path.unlink()
        message = str(error).splitlines()[0] if str(error) else type(error).__name__
        if writer:  # the other ranks meet the same error; rank 0 records and reports it
            mark_failed(output_dir, running, message)
            log.error("run failed: %s", message)
        if not isinstance(error, InputError):
            raise
        if writer:
            print(f"error: {error}", file=sys.stderr)
        if HydraConfig.get().mode == RunMode.MULTIRUN:  # one bad job must not end the sweep
            return float("nan")
        sys.exit(2)
    return run_score(metrics)


def run_score(metrics: dict) -> float:
    """The value a Hydra sweeper would optimise: validation, never test."""
    val = metrics.get("val", {})
    if "average" in val:
        return val["average"]["r2"]
    return val.get("accuracy", float("nan"))


def quiet_logging() -> None:
    """A rank other than 0: no log file (train.log is rank 0's), warnings and errors on the console."""
    root = logging.getLogger()
    for handler in [h for h in root.handlers if isinstance(h, logging.FileHandler)]:
        root.removeHandler(handler)
        handler.close()
    root.setLevel(logging.WARNING)


def terminated(signum, frame):
    raise SystemExit("terminated by SIGTERM (a scheduler's time limit or a kill)")


def as_input_error(error: InstantiationException) -> Exception:
    """A config key the target does not take (`+scene.sparkle=1`) or a value of the wrong type
    reaches the constructor as a TypeError inside Hydra's InstantiationException: name the key."""
    text = str(error)
    where = re.search(r"full_key: (\S+)", text)
    unexpected = re.search(r"unexpected keyword argument '(\w+)'", text)
    if unexpected:
        node = where.group(1) if where else "config"
        node = "scene" if node == "data.source" else node  # data=scene passes the scene as data.source
        return InputError(f"{node} has no parameter '{unexpected.group(1)}' (remove it or check its spelling)")
    cause = error.__cause__
    if isinstance(cause, InputError):
        return cause
    if isinstance(cause, (TypeError, ValueError)):
        return InputError(f"{where.group(1) if where else 'config'}: {str(cause).splitlines()[0]}")
    return error


def preflight(argv: list[str]) -> dict | None:
    """Compose the command's configuration once, before Hydra starts, so that a mistake is one
    line and exit code 2 in about a second (Hydra would print a multi-line message and exit 1,
    torch a traceback): an unknown option or key (also one added with `+` that its target does
    not take), a malformed override, a missing value, or a setting of the wrong type or out of
    range (runs/config_checks.py). The same composition names the folder this command will
    write into (hydra.run.dir, or hydra.sweep.dir for a sweep), which must hold nothing from an
    earlier run, or one folder would mix two runs' files: refused in one line, or cleared with
    overwrite=true (common/run_status.py), before Hydra writes .hydra/ and train.log into it.
    A sweep's axes are left to Hydra (runs/run.py checks each job's config); Hydra's other flags
    (--help, --cfg, ...) run nothing. Returns the run and sweep folders as composed (None for
    those flags)."""
    flags = {arg for arg in argv if arg.startswith("-")}
    if flags & {"--help", "-h"}:
        try:
            print(help_page(ROOT / "configs", composed([a for a in argv if not a.startswith("-")])), flush=True)
        except BrokenPipeError:   # `train.py --help | head`: the reader had enough, not an error
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        sys.exit(0)
    if flags - {"-m", "--multirun"}:
        return None
    try:
        overrides = OverridesParser.create().parse_overrides([arg for arg in argv if not arg.startswith("-")])
        sweep = bool(flags) or any(o.is_sweep_override() for o in overrides)
        with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
            cfg = compose(config_name="config", return_hydra_config=True,  # a sweep's folder does not depend on its axes
                          overrides=[o.input_line for o in overrides if not o.is_sweep_override()])
        sweep = sweep or cfg.hydra.mode == RunMode.MULTIRUN
        if not sweep:
            check_config(cfg)  # its warnings are logged by the run itself, once
        setting = "hydra.sweep.dir" if sweep else "hydra.run.dir"
        prepare_folder(Path(OmegaConf.select(cfg, setting)), setting, bool(cfg.overwrite))
        return {key: str(OmegaConf.select(cfg, key)) for key in FOLDER_SETTINGS}
    except InputError as error:
        print(f"error: {error}", file=sys.stderr)
        sys.exit(2)
    except Exception as error:  # Hydra's and OmegaConf's composition and override-parsing errors
        if flags:
            return None  # a sweep: Hydra reports its own errors before it makes a folder
        message = " ".join(str(error).split("Config search path")[0].split())
        hint = misspelt_setting(message, lambda key: composed([a for a in argv if not a.startswith("-")
                                                                and a.split("=", 1)[0].lstrip("+~") != key]))
        print(f"error: {hint or message}", file=sys.stderr)
        sys.exit(2)


def composed(arguments: list[str]) -> DictConfig:
    """The command's configuration as Hydra would compose it, a sweep's axes left out (the help
    page's values; the keys a misspelt setting could have meant)."""
    overrides = [o.input_line for o in OverridesParser.create().parse_overrides(arguments) if not o.is_sweep_override()]
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        return compose(config_name="config", return_hydra_config=True, overrides=overrides)


FOLDER_SETTINGS = ("hydra.run.dir", "hydra.sweep.dir")


def agree_on_run_folder(argv: list[str]) -> list[str]:
    """torchrun starts every rank with the same command, and each would name its own default
    folder (the time and its process id can differ): rank 0 checks the command (preflight) and
    names the folders, and every rank runs with them set explicitly -> the command line to run.
    The other ranks also leave .hydra/ to rank 0. An error ends every rank with rank 0's code."""
    from models.distributed import TrainingGroup, join_process_group
    join_process_group()
    group = TrainingGroup()
    outcome = None
    if group.is_writer:
        try:
            outcome = ("folders", preflight(argv))
        except SystemExit as stop:
            outcome = ("exit", stop.code)
    kind, value = group.agree(outcome)
    if kind == "exit":
        sys.exit(value)
    if value is None:  # --help, --cfg, ...: nothing to agree on
        return argv
    argv = [a for a in argv if a.split("=", 1)[0].lstrip("+") not in FOLDER_SETTINGS]
    argv += [f"{key}={hydra_quoted(folder)}" for key, folder in value.items()]
    return argv if group.is_writer else argv + ["hydra.output_subdir=null"]


def hydra_quoted(value: str) -> str:
    """A value as one quoted Hydra override value (a folder may hold characters Hydra parses)."""
    return "'" + value.replace("\\", "\\\\").replace("'", "\\'") + "'"


if __name__ == "__main__":
    if "--help-all" in sys.argv:   # Hydra's own page: every group and the whole config
        sys.argv = [a if a != "--help-all" else "--help" for a in sys.argv]
    elif launched_world_size() > 1:
        sys.argv[1:] = agree_on_run_folder(sys.argv[1:])
    else:
        preflight(sys.argv[1:])
    main()
