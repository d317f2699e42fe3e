"""Where a search's study lives, and joining it: one setting, `hydra.sweeper.storage`.

- `journal:///abs/path/study.log`, or any path ending in `.log`: Optuna's journal file (an
  append-only log that every worker replays; no server). Workers share it through any file
  system that all of them see (a local disk, NFS on a cluster: its lock is a symlink, which NFS
  honours). The default when `storage` is null: `multirun/studies/<study_name>.log` under the
  folder train.py is started from when the study is named (every search of the project started
  by hand with that name joins it), `<sweep dir>/study.log` when it is not (the sweep's own study).
- anything else: a SQLAlchemy URL for Optuna's RDBStorage: `postgresql+psycopg2://user@host/db`
  for a cluster (driver: requirements-postgres.txt), `sqlite:///path.db` on one machine. RDB
  storages record a heartbeat per running trial, so a trial whose worker died on any host is
  found stale and re-queued (lost_trials.py).

The first workers to open an empty database create its tables together and race (PostgreSQL
`UniqueViolation ... studydirection`, SQLite `table ... already exists`; Optuna issue #1092):
opening retries after a short random pause, by which time the winner's tables exist.
"""
import random
import re
import time
import warnings
from pathlib import Path

import optuna
from optuna.storages.journal import JournalFileBackend, JournalStorage

from common.errors import InputError

JOURNAL_SCHEME = "journal://"
STUDY_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")
SHARED_STUDIES = Path("multirun") / "studies"
OPEN_ATTEMPTS = 6


def storage_location(storage: str | None, study_name: str | None, sweep_dir: Path) -> str:
    """The storage setting as it will be opened: an absolute journal path or a SQLAlchemy URL."""
    if study_name is not None and not STUDY_NAME.fullmatch(study_name):
        raise InputError(f"hydra.sweeper.study_name={study_name!r}: use letters, digits, '_', '.', '-' "
                         "(it names the study's file)")
    if storage is None:
        path = SHARED_STUDIES / f"{study_name}.log" if study_name else sweep_dir / "study.log"
        return f"{JOURNAL_SCHEME}{path.absolute()}"
    if storage.startswith(JOURNAL_SCHEME) or storage.endswith(".log"):
        return f"{JOURNAL_SCHEME}{Path(storage.removeprefix(JOURNAL_SCHEME)).absolute()}"
    if "://" not in storage:
        raise InputError(f"hydra.sweeper.storage={storage}: neither a journal file (journal:///path.log or a "
                         "path ending in .log) nor a SQLAlchemy URL (postgresql+psycopg2://..., sqlite:///...)")
    return storage


def shown(location: str) -> str:
    """The location as logs and reports show it: a URL's password masked."""
    if location.startswith(JOURNAL_SCHEME):
        return location
    from sqlalchemy.engine import make_url
    return make_url(location).render_as_string(hide_password=True)


def open_storage(location: str, heartbeat_interval: int, retry_lost_trial) -> optuna.storages.BaseStorage:
    """The storage at `location` (storage_location), tables created once (see the module's note)."""
    if location.startswith(JOURNAL_SCHEME):
        path = Path(location.removeprefix(JOURNAL_SCHEME))
        path.parent.mkdir(parents=True, exist_ok=True)
        return JournalStorage(JournalFileBackend(str(path)))
    with warnings.catch_warnings():  # heartbeat_interval is "experimental" since Optuna 2.9
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        return retrying(lambda: optuna.storages.RDBStorage(
            location, heartbeat_interval=heartbeat_interval, grace_period=2 * heartbeat_interval,
            heartbeat_stale_trial_callback=retry_lost_trial), f"hydra.sweeper.storage={shown(location)}")


def retrying(open_once, what: str):
    """open_once() again after a random pause of up to 0.5 s while it fails, OPEN_ATTEMPTS in all;
    the last failure as one line."""
    for attempt in range(OPEN_ATTEMPTS):
        try:
            return open_once()
        except ImportError as error:  # a missing driver: no point retrying
            raise InputError(f"{what}: {error} (PostgreSQL: pip install -r requirements-postgres.txt)") from None
        except Exception as error:  # noqa: BLE001 - the schema race surfaces as several driver errors
            if attempt == OPEN_ATTEMPTS - 1:
                first = str(error).splitlines()[0] if str(error) else type(error).__name__
                raise InputError(f"{what}: cannot open it: {first}") from None
            time.sleep(random.uniform(0.05, 0.5))


def join_study(storage, study_name: str, sampler, direction: str, definition: dict) -> optuna.Study:
    """Create the study or load it; a study created with another definition (search space, fixed
    overrides, budget, seed, direction) is refused: its trials would not be comparable."""
    study = retrying(lambda: optuna.create_study(study_name=study_name, storage=storage, sampler=sampler,
                                                 direction=direction, load_if_exists=True),
                     f"study {study_name!r}")
    recorded = study.user_attrs.get("definition")
    if recorded is None:  # the first worker records it; two first workers both write, and re-read below
        study.set_user_attr("definition", definition)
        recorded = study.user_attrs["definition"]
    if recorded != definition:
        differing = sorted(k for k in definition.keys() | recorded.keys() if definition.get(k) != recorded.get(k))
        raise InputError(f"study {study_name!r} was started with other settings ({', '.join(differing)} differ: "
                         f"{ {k: recorded.get(k) for k in differing} }); join it with the same command, or "
                         "choose another hydra.sweeper.study_name")
    return study
