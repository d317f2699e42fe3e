"""What state a run folder is in, recorded by the run itself and read back by anything that lists runs.

Every run writes `status.json` first and last (train.py main()): `running` with its process id,
host, start time and config hash when it begins; `finished` only after every artefact is in place, or
`failed` with the one-line reason (also in `error.txt`, for grep). Each record replaces the
previous one atomically, so a reader sees one whole record. A run killed outright (kill -9,
power loss, a scheduler's time-out) cannot write its last record: its folder keeps saying
`running`, and `run_status` reads that as `interrupted` once the process is gone. This module is
the one writer of status.json and error.txt.

`prepare_folder` keeps a folder from mixing two runs: one named explicitly (hydra.run.dir,
hydra.sweep.dir) that holds anything is refused, or cleared when the user asks (overwrite=true).

Each folder's state: `python -m common.run_status outputs/*/* multirun/*/*/*`.
"""
import hashlib
import json
import os
import shutil
import socket
import sys
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

from omegaconf import DictConfig, OmegaConf

from common.atomic import atomic_write_json, atomic_write_text
from common.errors import InputError

STATUS_FILE = "status.json"
ERROR_FILE = "error.txt"
PROC = Path("/proc")


@dataclass(frozen=True)
class RunStatus:
    state: str        # finished, failed, running, interrupted, or unknown (no status.json)
    reason: str = ""  # why it failed, why it reads interrupted or unknown, where it runs


def _now() -> str:
    return datetime.now().astimezone().isoformat(timespec="seconds")


def _process_start(pid: int) -> str | None:
    """When process `pid` started, as '<boot id>:<clock ticks since boot>' (Linux /proc): a process
    that later reuses the pid, after this one ended or after a reboot, has another. None when no
    such process is alive (zombies count as gone) or there is no /proc to ask."""
    try:
        boot = (PROC / "sys" / "kernel" / "random" / "boot_id").read_text().strip()
        stat = (PROC / str(pid) / "stat").read_text()
    except OSError:
        return None
    state, *fields = stat[stat.rindex(")") + 2:].split()  # the command name in () may hold spaces
    return None if state in ("Z", "X") else f"{boot}:{fields[18]}"  # field 22 of proc(5): starttime


def _is_alive(pid: int, process_start: str | None) -> bool:
    if process_start is not None:
        return _process_start(pid) == process_start
    try:  # no /proc where the run was written (macOS): the pid alone, which a later process may reuse
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # alive, another user's
        return True
    return True


def this_process() -> dict:
    """This process as {pid, host, process_start}: enough for `process_state` to tell later, from
    another process, whether it still runs (run folders and search trials record it)."""
    pid = os.getpid()
    return {"pid": pid, "host": socket.gethostname(), "process_start": _process_start(pid)}


def process_state(record: dict) -> str:
    """`alive`, `gone` or `elsewhere` (another host: cannot be checked from here) for a process
    that `this_process` recorded."""
    if record["host"] != socket.gethostname():
        return "elsewhere"
    return "alive" if _is_alive(int(record["pid"]), record.get("process_start")) else "gone"


def config_hash(config: DictConfig) -> str:
    """A run's composed configuration, as .hydra/config.yaml holds it (interpolations unresolved),
    as 16 hex digits of SHA-256 over its canonical JSON: neither key order nor YAML formatting
    changes it, any value does. Take it before the run: instantiating parts of a config can
    resolve interpolations in place (${seed} becomes 0)."""
    canonical = json.dumps(OmegaConf.to_container(config, resolve=False), sort_keys=True)
    return hashlib.sha256(canonical.encode()).hexdigest()[:16]


def mark_running(folder, configuration_hash: str) -> dict:
    """The first record of a run: which process on which host, since when, with which
    configuration (config_hash). Returns it, for the last record."""
    record = {"state": "running", **this_process(), "started": _now(), "config_hash": configuration_hash}
    atomic_write_json(Path(folder) / STATUS_FILE, record)
    return record


def mark_finished(folder, running: dict) -> None:
    """The last record of a run whose every artefact is in place."""
    atomic_write_json(Path(folder) / STATUS_FILE, {**running, "state": "finished", "ended": _now()})


def mark_failed(folder, running: dict, reason: str) -> None:
    """The last record of a run that failed: the one-line reason in error.txt and in the status."""
    atomic_write_text(Path(folder) / ERROR_FILE, f"{reason}\n")
    atomic_write_json(Path(folder) / STATUS_FILE, {**running, "state": "failed", "ended": _now(), "reason": reason})


def run_status(folder) -> RunStatus:
    """The state of the run in `folder`: what its status.json says, except that a run recorded as
    running whose process is gone (same host; pid dead or now another process's) is `interrupted`.
    A run on another host cannot be checked from here and reads `running`."""
    path = Path(folder) / STATUS_FILE
    try:
        record = json.loads(path.read_text())
        state = record["state"]
        if state == "running":
            pid, host = int(record["pid"]), record["host"]
    except FileNotFoundError:
        return RunStatus("unknown", f"no {STATUS_FILE} (not a run folder, or stopped before its run began)")
    except (OSError, ValueError, KeyError, TypeError) as error:
        return RunStatus("unknown", f"unreadable {STATUS_FILE}: {type(error).__name__} {error}")
    if state == "failed":
        return RunStatus("failed", record.get("reason", ""))
    if state != "running":
        return RunStatus(state)
    where = f"pid {pid} on {host}, started {record.get('started', '?')}"
    process = process_state(record)
    if process == "elsewhere":
        return RunStatus("running", f"{where}; cannot check another host from here")
    if process == "alive":
        return RunStatus("running", where)
    return RunStatus("interrupted", f"{where}: the process ended without recording an end (killed?)")


def prepare_folder(folder, setting: str, overwrite: bool) -> None:
    """Before anything is written into `folder` (the value of `setting`, hydra.run.dir or
    hydra.sweep.dir): an absent or empty folder is used as it is; one holding anything is refused
    (InputError), or with `overwrite` cleared, but only when it is a run or a sweep (.hydra/,
    status.json or multirun.yaml in it), no run in it is still running, and it does not hold the
    working directory: overwrite=true with a mistyped folder must not delete a user's files."""
    folder = Path(folder).absolute()
    if not folder.exists() or (folder.is_dir() and not any(folder.iterdir())):
        return
    if not folder.is_dir():
        raise InputError(f"{setting}={folder} is a file, not a folder")
    is_run = (folder / ".hydra").is_dir() or (folder / STATUS_FILE).is_file()
    is_sweep = (folder / "multirun.yaml").is_file()
    names = sorted(p.name for p in folder.iterdir())
    what = (f"an earlier run ({run_status(folder).state})" if is_run else "an earlier sweep" if is_sweep
            else f"other files ({', '.join(names[:3])}{', ...' if len(names) > 3 else ''})")
    if not overwrite:
        raise InputError(f"{setting}={folder} already holds {what}; choose another folder, or add overwrite=true "
                         "to replace it")
    running = [p for p in (folder, *folder.iterdir()) if p.is_dir() and run_status(p).state == "running"]
    if running:
        raise InputError(f"{setting}={folder}: the run in {running[0]} is still running "
                         f"({run_status(running[0]).reason}); not clearing it")
    if not (is_run or is_sweep):
        raise InputError(f"{setting}={folder} holds {what} but no run or sweep (.hydra/, {STATUS_FILE}, "
                         "multirun.yaml); not clearing it")
    if Path.cwd().resolve().is_relative_to(folder.resolve()):
        raise InputError(f"{setting}={folder} holds the working directory; not clearing it")
    shutil.rmtree(folder)


if __name__ == "__main__":
    for name in sys.argv[1:]:
        status = run_status(name)
        print(f"{name}\t{status.state}" + (f"\t{status.reason}" if status.reason else ""))
