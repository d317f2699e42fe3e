"""Result records: every number Touchstone reports about itself, as data with its provenance.

A bench measures, then appends one record per thing it measured to `results/<bench>.jsonl`
(one JSON object per line, committed with the code). A record carries the raw values (per seed
or split, not only their mean ± sd) and everything needed to judge them: the exact command, the
git commit and whether the tree was dirty, the lock's hash, package versions, CPU, cores,
threads, the 1-minute load average before and after, the date, the seeds, and a hash of each
source path the bench declares as the code it measures (so the docs can say **stale** when that
code changes after the measurement). The docs generator (docs/generate.py) reads them back and
renders every table of measured numbers; nothing else writes these files.

    with recording("default_run", measured_code=["models/", "train.py"]) as record:
        record.add("scores", {"r2_by_seed": [...]}, seeds=[0, 1, 2])

A line that is not a whole record (truncated, hand-edited, a missing field) is refused with one
line naming the file and the line: a table is never drawn from half a record.
"""
import ast
import functools
import hashlib
import json
import math
import os
import platform
import shlex
import subprocess
import sys
from contextlib import contextmanager
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path

import yaml

from common.atomic import atomic_write_text

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results"
LOCK = ROOT / "requirements.lock"
SCHEMA = 1
# The packages whose versions move numbers; every record names them (the lock pins the rest).
VERSIONED = ("torch", "numpy", "scikit-learn", "scipy", "onnxruntime", "pandas")
FIELDS = {"schema": int, "bench": str, "name": str, "values": dict, "seeds": list, "command": str,
          "commit": str, "dirty": bool, "lock_sha256": str, "measured_code": dict, "versions": dict,
          "machine": dict, "load_before": float, "load_after": float, "date": str, "duration_s": float}
CODE_SUFFIXES = {".py", ".yaml", ".yml"}
# The recorder itself measures nothing: editing it must not make every record under common/ stale.
NOT_MEASURED = {"common/result_records.py"}


class RecordError(ValueError):
    """A results file or record that cannot be used; the message is one line naming the file."""


def file_sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def lock_sha256() -> str:
    return file_sha256(LOCK) if LOCK.is_file() else "no-lock"


def _sources_now(path: str) -> dict[str, bytes]:
    """The measured source files a path names today: the file itself, or every .py/.yaml file
    under a folder (the recorder excepted), keyed by repository-relative name."""
    target = ROOT / path
    if target.is_file():
        return {path: target.read_bytes()}
    if not target.is_dir():
        raise RecordError(f"measured code {path!r} does not exist under {ROOT}")
    return {name: file.read_bytes() for file in sorted(target.rglob("*"))
            if (name := file.relative_to(ROOT).as_posix()) and file.suffix in CODE_SUFFIXES
            and "__pycache__" not in file.parts and file.is_file() and name not in NOT_MEASURED}


@functools.lru_cache(maxsize=None)
def _sources_at(commit: str, path: str) -> dict[str, bytes] | None:
    """The same files as git holds them at a commit (None when git or the commit is missing);
    cached, as a commit never changes and the docs ask for the same pair once per record."""
    listed = _git("ls-tree", "-r", "--name-only", commit, "--", path.rstrip("/"))
    if not listed:
        return None
    names = [name for name in listed.splitlines()
             if name == path or (path.endswith("/") and Path(name).suffix in CODE_SUFFIXES and name not in NOT_MEASURED)]
    sources = {}
    for name in names:
        shown_file = subprocess.run(["git", "show", f"{commit}:{name}"], cwd=ROOT, capture_output=True)
        if shown_file.returncode != 0:
            return None
        sources[name] = shown_file.stdout
    return sources


def _digest(path: str, sources: dict[str, bytes]) -> str:
    """A file's sha256, or for a folder one sha256 over its files' names and bytes, sorted."""
    if not path.endswith("/") and list(sources) == [path]:
        return hashlib.sha256(sources[path]).hexdigest()
    digest = hashlib.sha256()
    for name in sorted(sources, key=lambda name: Path(name).parts):  # the order rglob sorts in
        digest.update(name.encode() + b"\0" + sources[name] + b"\0")
    return digest.hexdigest()


def code_sha256(path: str) -> str:
    """Hash of the source a path names, so a record can tell whether the code it measured changed."""
    return _digest(path, _sources_now(path))


@functools.lru_cache(maxsize=4096)
def _meaning(name: str, source: bytes):
    """What a source file does, without its comments and docstrings: a comment or a docstring
    edited after a measurement (a renamed test path, a clearer sentence) changes no number."""
    if name.endswith(".py"):
        try:
            tree = ast.parse(source)
        except SyntaxError:
            return source
        for node in ast.walk(tree):
            body = getattr(node, "body", None)
            if isinstance(body, list) and body and isinstance(body[0], ast.Expr) \
                    and isinstance(body[0].value, ast.Constant) and isinstance(body[0].value.value, str):
                node.body = body[1:] or [ast.Pass()]
        return ast.dump(tree)
    try:
        return json.dumps(yaml.safe_load(source), sort_keys=True, default=str)
    except yaml.YAMLError:
        return source


def changed_code(record: dict) -> list[str]:
    """The measured paths whose code differs from what the record measured (empty: current).
    Bytes equal: current. Otherwise git's copy at the record's commit, when its hash is the one
    recorded (so it is what was measured), is compared without comments and docstrings."""
    changed = []
    for path, sha in record["measured_code"].items():
        if not (ROOT / path).exists():
            changed.append(path)
            continue
        now = _sources_now(path)
        if _digest(path, now) == sha:
            continue
        then = _sources_at(record["commit"], path) if record["commit"] else None
        if then is None or _digest(path, then) != sha or set(then) != set(now) \
                or any(_meaning(name, then[name]) != _meaning(name, now[name]) for name in now):
            changed.append(path)
    return changed


def _git(*args) -> str:
    done = subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True)
    return done.stdout.strip() if done.returncode == 0 else ""


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _versions() -> dict:
    versions = {"python": platform.python_version()}
    for package in VERSIONED:
        try:
            versions[package] = metadata.version(package)
        except metadata.PackageNotFoundError:
            versions[package] = "absent"
    return versions


def _threads() -> int:
    """Threads the measured code may use: the bench's own setting, as train.py reads it."""
    for variable in ("OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        if os.environ.get(variable, "").isdigit():
            return int(os.environ[variable])
    return os.cpu_count() or 1


def plain(value):
    """JSON's own types from numpy's (arrays to lists, scalars to numbers); a non-finite float
    becomes null, which JSON can hold and NaN it cannot."""
    if isinstance(value, dict):
        return {str(key): plain(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(item) for item in value]
    if hasattr(value, "tolist"):              # numpy array or scalar
        return plain(value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


class Recording:
    """What one bench run measured; written when the `with` block ends without an error."""

    def __init__(self, bench: str, measured_code: list[str], command: str | None = None):
        self.bench, self.records = bench, []
        self.measured_code = {path: code_sha256(path) for path in measured_code}
        self.command = command or shlex.join(["python", *sys.argv])
        self.started = datetime.now(timezone.utc)
        self.load_before = os.getloadavg()[0]

    def add(self, name: str, values: dict, seeds: list | None = None):
        """One measured thing: `values` holds the raw numbers (per seed or split, as lists)."""
        self.records.append({"name": name, "values": plain(values), "seeds": plain(list(seeds or []))})

    def finish(self) -> Path:
        load_after = os.getloadavg()[0]
        # results/ is what benches write, not code: a tree dirty only there measured committed code.
        status = _git("status", "--porcelain", "--untracked-files=no", "--", ".", ":!results")
        common = {"schema": SCHEMA, "bench": self.bench, "command": self.command,
                  "commit": _git("rev-parse", "HEAD") or "unknown", "dirty": bool(status),
                  "lock_sha256": lock_sha256(), "measured_code": self.measured_code, "versions": _versions(),
                  "machine": {"cpu": _cpu_model(), "cores": os.cpu_count() or 1, "threads": _threads(),
                              "host": platform.node()},
                  "load_before": round(self.load_before, 2), "load_after": round(load_after, 2),
                  "date": self.started.isoformat(timespec="seconds"),
                  "duration_s": round((datetime.now(timezone.utc) - self.started).total_seconds(), 1)}
        return append_records(self.bench, [{**common, **record} for record in self.records])


@contextmanager
def recording(bench: str, measured_code: list[str], command: str | None = None):
    """`with recording(bench, measured_code) as record:` ... `record.add(...)`: appended when the
    block ends, and only if it ends without an error (a failed bench records nothing)."""
    record = Recording(bench, measured_code, command)
    yield record
    if record.records:
        path = record.finish()
        print(f"recorded {len(record.records)} result(s) in {path.relative_to(ROOT)}", flush=True)


def append_records(bench: str, records: list[dict], results: Path | None = None) -> Path:
    """The one writer of results files: the old lines (checked) plus the new, moved into place whole."""
    path = (results or RESULTS) / f"{bench}.jsonl"
    old = read_records(path) if path.exists() else []
    for number, record in enumerate(records, start=1):
        check_record(record, f"{shown(path)} (new record {number})")
    # Keys keep the order the bench wrote them in (targets, candidates): tables print in that order.
    lines = [json.dumps(record, allow_nan=False) for record in old + records]
    atomic_write_text(path, "\n".join(lines) + "\n")
    return path


def check_record(record, where: str) -> dict:
    if not isinstance(record, dict):
        raise RecordError(f"{where}: not a JSON object")
    missing = [key for key in FIELDS if key not in record]
    if missing:
        raise RecordError(f"{where}: missing field(s) {', '.join(missing)}")
    for key, kind in FIELDS.items():
        value = record[key]
        if kind is float and isinstance(value, int) and not isinstance(value, bool):
            continue
        if not isinstance(value, kind) or (kind is int and isinstance(value, bool)):
            raise RecordError(f"{where}: field {key!r} should be {kind.__name__}, got {type(value).__name__}")
    if record["schema"] != SCHEMA:
        raise RecordError(f"{where}: schema {record['schema']}, this code reads {SCHEMA}")
    return record


def shown(path: Path) -> str:
    """A path as a message names it: relative to the repository when it lies inside."""
    path = Path(path)
    return str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path)


def read_records(path: Path) -> list[dict]:
    """Every record of one results file, each checked; the first bad line stops it with its number."""
    path = Path(path)
    where = shown(path)
    if not path.is_file():
        raise RecordError(f"{where}: no such results file")
    records = []
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except json.JSONDecodeError as error:
            raise RecordError(f"{where}:{number}: not a whole JSON record ({error.msg})") from None
        records.append(check_record(record, f"{where}:{number}"))
    if not records:
        raise RecordError(f"{where}: holds no record")
    return records


def _pins(lock_text: str) -> dict[str, str]:
    """package -> the whole pinned entry (version and hashes) of a pip-compile lock."""
    pins, current = {}, None
    for line in lock_text.splitlines():
        if line and not line[0].isspace() and "==" in line:
            current = line.split("==", 1)[0].strip().lower()
            pins[current] = line.strip().rstrip("\\").strip()
        elif current and line.strip().startswith("--hash="):
            pins[current] += " " + line.strip().rstrip("\\").strip()
    return pins


@functools.lru_cache(maxsize=None)
def _lock_grew_since(commit: str, recorded_sha: str, current_sha: str) -> bool:
    then = _sources_at(commit, "requirements.lock") if commit else None
    if not then or hashlib.sha256(then["requirements.lock"]).hexdigest() != recorded_sha:
        return False
    old, new = _pins(then["requirements.lock"].decode()), _pins(LOCK.read_text())
    return bool(old) and all(new.get(name) == pinned for name, pinned in old.items())


def lock_only_grew(record: dict) -> bool:
    """A record measured under an earlier lock still stands when today's lock pins every package
    that lock pinned, at the same version and hashes, and only adds packages (pyserial for
    predict.py's serial input moves no measured number). The earlier lock is git's copy at the
    record's commit, used only when its hash is the recorded one."""
    return _lock_grew_since(record["commit"], record["lock_sha256"], lock_sha256())


def latest(bench: str, name: str, results: Path | None = None) -> dict:
    """The newest record called `name` of one bench; refused when it was measured under another lock."""
    path = (results or RESULTS) / f"{bench}.jsonl"
    found = [record for record in read_records(path) if record["name"] == name]
    if not found:
        raise RecordError(f"{shown(path)}: no record named {name!r}")
    record = found[-1]
    if record["lock_sha256"] != lock_sha256() and not lock_only_grew(record):
        raise RecordError(f"{shown(path)}: record {name!r} was measured under lock {record['lock_sha256'][:12]}, "
                          f"requirements.lock is now {lock_sha256()[:12]}: re-measure it (make bench)")
    return record


def differences(recorded, fresh, digits: int = 4, where: str = "") -> list[str]:
    """Where two results differ in the digits a run prints (floats rounded to `digits` decimals;
    names, counts and nesting exactly): empty when a re-run reproduces a record."""
    if isinstance(recorded, dict) and isinstance(fresh, dict):
        keys = sorted(set(recorded) | set(fresh))
        return [line for key in keys for line in differences(recorded.get(key), fresh.get(key), digits, f"{where}/{key}")]
    if isinstance(recorded, list) and isinstance(fresh, list) and len(recorded) == len(fresh):
        return [line for i, (a, b) in enumerate(zip(recorded, fresh))
                for line in differences(a, b, digits, f"{where}[{i}]")]
    if isinstance(recorded, float) and isinstance(fresh, float):
        same = round(recorded, digits) == round(fresh, digits)
    else:
        same = recorded == fresh
    return [] if same else [f"{where or '/'}: recorded {recorded!r}, now {fresh!r}"]
