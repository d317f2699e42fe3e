"""The fidelity table's parts: observations registered per scene, what a measurement returns,
and the table. One check function per observation in ../shared/notes/seed-observations.md,
registered with `@observation(scene, number, statement, paper)` in `CHECKS[scene]`; each returns
a `Measured`. bench/fidelity.py prints the table; the tests assert every row that holds.

Each scene's checks live in their own module (`SCENE_MODULES`); `load_scene` imports it, so a
scene whose module is not written yet is reported as such instead of failing the others. A
check gets a probe: the class the module registers with `@probe(scene)`, or else `SceneConfig`
(the composed scene config as a dict, `params`, and `repeats`), built from the scene's config
`CONFIGS[scene]` plus any Hydra overrides. Rows measured on a scene's random draws are measured
at each of `SEEDS` and reported as mean ± sd (`judged_over_seeds`)."""
import importlib
from dataclasses import dataclass, field
from pathlib import Path

from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf

from runs.fidelity.registered import registration

ROOT = Path(__file__).resolve().parents[2]
# seed 000, 003, 001, 002, 004 (../shared/notes/seed-observations.md)
CHECKS: dict[str, list] = {"rubber12": [], "fingertip": [], "capacitive6x6": [], "ert": [], "taxels": []}
SCENE_MODULES = {"rubber12": "runs.fidelity.rubber12", "fingertip": "runs.fidelity.fingertip",
                 "capacitive6x6": "runs.fidelity.capacitive6x6", "ert": "runs.fidelity.ert",
                 "taxels": "runs.fidelity.taxels"}
CONFIGS = {"rubber12": "rubber12", "fingertip": "fingertip", "capacitive6x6": "capacitive6x6",
           "ert": "ert_indentation_internal", "taxels": "taxels"}
PROBES: dict[str, type] = {}
SEEDS = (0, 1, 2)   # scene seeds (specimen, noise draws) the rows of rubber12 and fingertip are measured over


@dataclass
class Measured:
    value: str                      # the scene's measurement, in words with units
    holds: bool | None              # None: not measured by this table (value says why)
    tolerance: str = ""
    numbers: dict = field(default_factory=dict)
    unsupported: str = ""           # not empty: the paper cannot support the row (what it leaves out)


@dataclass
class Row:
    scene: str
    number: str
    statement: str
    paper: str
    measured: Measured


def observation(scene: str, number: str, statement: str, paper: str = "—"):
    """Register a check function as the measurement of one observation of `scene`'s paper."""
    def register(fn):
        fn.observation = (scene, number, statement, paper)
        CHECKS.setdefault(scene, []).append(fn)
        return fn
    return register


def probe(scene: str):
    """Register the class whose instances `(params, repeats=...)` the checks of `scene` get."""
    def register(cls):
        PROBES[scene] = cls
        return cls
    return register


class SceneConfig:
    """The probe of a scene whose module registers none: its composed config and a sample size."""

    def __init__(self, params: dict, repeats: int = 20):
        self.params = {k: v for k, v in params.items() if k not in ("_target_", "_convert_")}
        self.repeats = repeats


def load_scene(scene: str) -> bool:
    """Import the module holding `scene`'s checks; False when it does not exist yet."""
    name = SCENE_MODULES[scene]
    try:
        importlib.import_module(name)
    except ModuleNotFoundError as error:
        if error.name != name:      # the module exists but something it imports does not
            raise
        return False
    return True


def make_probe(scene: str, overrides=(), repeats: int | None = None, config: str | None = None):
    """The probe of `scene` on its config (or `config`) with Hydra `overrides`; `repeats` None:
    the probe's own default sample size (each scene's paper's)."""
    size = {} if repeats is None else {"repeats": repeats}
    return PROBES.get(scene, SceneConfig)(scene_params(config or CONFIGS[scene], overrides), **size)


def row_order(number: str) -> tuple[int, str]:
    """'3a' -> (3, 'a'): rows in the paper's order whichever module registered them."""
    digits = number.rstrip("abcdefghijklmnopqrstuvwxyz")
    return int(digits), number[len(digits):]


def run_checks(scene: str, probe) -> list[Row]:
    """Measure every row of `scene`; every row is pre-registered from the paper
    (runs/fidelity/registered/) and must be judged by its registered tolerance, and a row the paper
    cannot support says so. A row with no registration is refused before anything is measured."""
    checks = sorted(CHECKS[scene], key=lambda fn: row_order(fn.observation[1]))
    unregistered = [f"{fn.observation[0]}/{fn.observation[1]}" for fn in checks
                    if registration(fn.observation[0], fn.observation[1]) is None]
    if unregistered:
        raise RuntimeError(f"fidelity rows {', '.join(unregistered)} are not registered: register the paper's words, "
                           "the statistic and the tolerance in runs/fidelity/registered/ first")
    rows = []
    for fn in checks:
        name, number, statement, paper = fn.observation
        measured = fn(probe)
        registered = registration(name, number)
        if measured.holds is not None and not measured.tolerance.startswith(registered.tolerance):
            raise RuntimeError(f"fidelity row {name}/{number} was judged by '{measured.tolerance}', not by its "
                               f"registered tolerance '{registered.tolerance}' (runs/fidelity/registered/)")
        measured.unsupported = registered.missing
        rows.append(Row(name, number, statement, paper, measured))
    return rows


def verdict(measured: Measured) -> str:
    if measured.unsupported:
        return "not supported by the paper"
    return {True: "holds", False: "does not hold", None: "not measured"}[measured.holds]


def seeds_label(seeds) -> str:
    return f"seed {seeds[0]}" if len(seeds) == 1 else f"seeds {seeds[0]}-{seeds[-1]}"


def judged_over_seeds(value: str, holds_at_seed, holds_on_mean: bool, tolerance: str, seeds,
                      numbers: dict) -> Measured:
    """A row measured at several scene seeds holds when it holds on the mean over the seeds and at
    every seed; where the two disagree (a row that flips on a seed) the value says at which seeds it
    holds and whether on the mean."""
    holds_at_seed = [bool(h) for h in holds_at_seed]
    holds = bool(holds_on_mean) and all(holds_at_seed)
    if not holds and (holds_on_mean or any(holds_at_seed)):
        held = [str(s) for s, h in zip(seeds, holds_at_seed) if h]
        value += (f"; flips across seeds: holds at {len(held)} of {len(seeds)} ({', '.join(held) or 'none'}), "
                  f"{'and' if holds_on_mean else 'not'} on the mean")
    return Measured(value, holds, f"{tolerance}, on the mean and at every seed", numbers)


def scene_params(config: str, overrides=()) -> dict:
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        composed = compose("config", overrides=[f"scene={config}", "seed=0", *overrides])
    return OmegaConf.to_container(composed.scene, resolve=True)


def markdown(rows) -> str:
    lines = ["| # | paper's observation | paper's number | scene's measurement | tolerance | verdict |",
             "|---|---|---|---|---|---|"]
    for row in rows:
        m = row.measured
        lines.append(f"| {row.number} | {row.statement} | {row.paper} | {m.value} | {m.tolerance or '—'} | "
                     f"{verdict(m)} |")
    return "\n".join(lines)
