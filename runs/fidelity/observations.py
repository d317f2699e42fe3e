"""The fidelity table's parts: observations registered per scene, what a measurement returns,
and the table. One check function per observation in ../shared/notes/seed-observations.md,
registered with `@observation(scene, number, statement, paper)` in `CHECKS[scene]`; each returns
a `Measured`. bench/fidelity.py prints the table; the tests assert every row that holds."""
from dataclasses import dataclass, field
from pathlib import Path

from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf

ROOT = Path(__file__).resolve().parents[2]
CHECKS: dict[str, list] = {"rubber12": [], "fingertip": []}


@dataclass
class Measured:
    value: str                      # the scene's measurement, in words with units
    holds: bool | None              # None: not measured by this table (value says why)
    tolerance: str = ""
    numbers: dict = field(default_factory=dict)


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
        CHECKS[scene].append(fn)
        return fn
    return register


def run_checks(scene: str, probe) -> list[Row]:
    rows = []
    for fn in CHECKS[scene]:
        name, number, statement, paper = fn.observation
        rows.append(Row(name, number, statement, paper, fn(probe)))
    return rows



def scene_params(config: str, overrides=()) -> dict:
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        composed = compose("config", overrides=[f"scene={config}", "seed=0", *overrides])
    return OmegaConf.to_container(composed.scene, resolve=True)


def markdown(rows) -> str:
    verdict = {True: "holds", False: "does not hold", None: "not measured"}
    lines = ["| # | paper's observation | paper's number | scene's measurement | tolerance | verdict |",
             "|---|---|---|---|---|---|"]
    for row in rows:
        m = row.measured
        lines.append(f"| {row.number} | {row.statement} | {row.paper} | {m.value} | {m.tolerance or '—'} | "
                     f"{verdict[m.holds]} |")
    return "\n".join(lines)
