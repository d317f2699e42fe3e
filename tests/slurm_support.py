"""A one-node SLURM cluster for one test (tests/runs/test_shared_search.py): Debian's slurm-wlm daemons
(slurmctld, slurmd) and a private munge daemon, all in a temporary folder with their own socket and
ports, stopped by their process ids when the `with` block ends. Needs root (slurmd starts jobs as
their user), as in CI; `SLURM_CONF` in the yielded environment points sbatch, squeue and submitit
at it.
"""
import os
import shutil
import socket
import subprocess
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

HOW_TO_ENABLE = ("SLURM not found: as root, apt-get install slurmctld slurmd slurm-client munge to run it")
DAEMONS = ("munged", "slurmctld", "slurmd", "sbatch", "sinfo")


def missing() -> str | None:
    if os.geteuid() != 0 or any(shutil.which(d) is None and not Path("/usr/sbin", d).is_file() for d in DAEMONS):
        return HOW_TO_ENABLE
    return None


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@contextmanager
def throwaway_slurm(cpus: int = 2):
    """Yields the environment (os.environ plus SLURM_CONF) under which jobs go to partition `debug`."""
    folder = Path(tempfile.mkdtemp(prefix="touchstone-slurm-"))
    for sub in ("state", "spool", "log"):
        (folder / sub).mkdir()
    key = folder / "munge.key"
    key.write_bytes(os.urandom(1024))
    key.chmod(0o600)
    munge_socket, host = folder / "munge.socket", socket.gethostname()
    conf = folder / "slurm.conf"
    conf.write_text("\n".join([
        "ClusterName=touchstone", f"SlurmctldHost={host}", "SlurmUser=root", "SlurmdUser=root",
        "AuthType=auth/munge", f"AuthInfo=socket={munge_socket}", f"SlurmctldPort={free_port()}",
        f"SlurmdPort={free_port()}", "ProctrackType=proctrack/linuxproc", "TaskPlugin=task/none",
        f"StateSaveLocation={folder / 'state'}", f"SlurmdSpoolDir={folder / 'spool'}",
        f"SlurmctldPidFile={folder / 'slurmctld.pid'}", f"SlurmdPidFile={folder / 'slurmd.pid'}",
        f"SlurmctldLogFile={folder / 'log' / 'slurmctld.log'}", f"SlurmdLogFile={folder / 'log' / 'slurmd.log'}",
        "SchedulerType=sched/builtin", "SelectType=select/cons_tres", "SelectTypeParameters=CR_Core",
        "ReturnToService=2", "JobCompType=jobcomp/none", "AccountingStorageType=accounting_storage/none",
        "MpiDefault=none", f"NodeName={host} CPUs={cpus} State=UNKNOWN",
        "PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP", ""]))
    env = {**os.environ, "SLURM_CONF": str(conf)}
    pid_files = [folder / "munged.pid", folder / "slurmctld.pid", folder / "slurmd.pid"]
    try:
        subprocess.run(["munged", "--force", f"--socket={munge_socket}", f"--key-file={key}",
                        f"--pid-file={pid_files[0]}", f"--log-file={folder / 'log' / 'munged.log'}",
                        f"--seed-file={folder / 'munged.seed'}"], check=True, capture_output=True, timeout=30)
        subprocess.run(["slurmctld", "-f", str(conf)], check=True, capture_output=True, env=env, timeout=30)
        subprocess.run(["slurmd", "-f", str(conf)], check=True, capture_output=True, env=env, timeout=30)
        deadline = time.monotonic() + 60
        while "idle" not in subprocess.run(["sinfo", "-h", "-o", "%t"], capture_output=True, text=True,
                                           env=env).stdout:
            if time.monotonic() > deadline:
                raise RuntimeError(f"SLURM did not come up: {(folder / 'log' / 'slurmctld.log').read_text()[-500:]}")
            time.sleep(0.2)
        yield env
    finally:
        for pid_file in reversed(pid_files):  # the daemons this block started, by their own pid files
            if pid_file.is_file():
                try:
                    os.kill(int(pid_file.read_text().split()[0]), 15)
                except (ProcessLookupError, ValueError):
                    pass
        time.sleep(0.5)
        shutil.rmtree(folder, ignore_errors=True)
