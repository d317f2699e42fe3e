"""A PostgreSQL server for one test or measurement of a shared search (tests/runs/test_shared_search.py,
bench/search_scaling.py): a fresh cluster in a temporary folder, reachable only through a Unix
socket there (no TCP port, nothing outside touched), removed when the `with` block ends.

Uses Debian's `postgresql` package (initdb and pg_ctl on PATH or under /usr/lib/postgresql/<v>/bin)
and the psycopg2 driver (requirements-postgres.txt). initdb refuses to run as root, so as root the
server runs as the `postgres` user the package creates (runuser), in a folder it may enter.
"""
import os
import shutil
import subprocess
import tempfile
from contextlib import contextmanager
from pathlib import Path

HOW_TO_ENABLE = ("PostgreSQL not found: apt-get install postgresql and pip install -r requirements-postgres.txt "
                 "to run it")


def server_binaries() -> Path | None:
    """The folder holding initdb and pg_ctl, or None."""
    on_path = shutil.which("initdb")
    candidates = [Path(on_path).resolve().parent] if on_path else []
    candidates += sorted(Path("/usr/lib/postgresql").glob("*/bin"), reverse=True)
    return next((c for c in candidates if (c / "initdb").is_file() and (c / "pg_ctl").is_file()), None)


def missing() -> str | None:
    """Why no throwaway server can start here (HOW_TO_ENABLE), or None when one can."""
    try:
        import psycopg2  # noqa: F401 - the driver SQLAlchemy loads for postgresql+psycopg2://
    except ImportError:
        return HOW_TO_ENABLE
    if server_binaries() is None or (os.geteuid() == 0 and shutil.which("runuser") is None):
        return HOW_TO_ENABLE
    return None


@contextmanager
def throwaway_postgres(durable: bool = False):
    """Yields the SQLAlchemy URL of a fresh, empty server (database `postgres`). Not `durable`
    (tests): fsync off, as nothing outlives the test; `durable` (measurements): the server's
    default durability, every commit flushed to disk as on a real database server."""
    binaries = server_binaries()
    as_root = os.geteuid() == 0
    user = "postgres" if as_root else os.environ.get("USER") or Path.home().name
    folder = Path(tempfile.mkdtemp(prefix="touchstone-pg-"))
    data, socket_dir = folder / "data", folder / "socket"
    socket_dir.mkdir()
    if as_root:
        shutil.chown(folder, "postgres")
        shutil.chown(socket_dir, "postgres")
    prefix = ["runuser", "-u", "postgres", "--"] if as_root else []
    port = 40000 + os.getpid() % 20000  # names the socket file only: no TCP listener

    def run(*command):
        subprocess.run(prefix + [str(binaries / command[0]), *command[1:]], check=True, capture_output=True,
                       text=True, timeout=120)

    try:
        run("initdb", "-A", "trust", "--no-sync", "-U", user, "-D", str(data))
        run("pg_ctl", "-D", str(data), "-l", str(folder / "server.log"), "-w",
            "-o", f"-k {socket_dir} -p {port} -c listen_addresses=''" + ("" if durable else " -c fsync=off"), "start")
        try:
            yield f"postgresql+psycopg2://{user}@/postgres?host={socket_dir}&port={port}"
        finally:
            run("pg_ctl", "-D", str(data), "-m", "immediate", "-w", "stop")
    finally:
        shutil.rmtree(folder, ignore_errors=True)
