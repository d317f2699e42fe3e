"""The fidelity rows pre-registered from the papers: for each row, the paper's own words (quoted),
the statistic that measures it and the tolerance it is judged by, written down before the row is
measured and frozen (tests/runs/fidelity/test_registered.py: a tolerance changes only with a new
quote). A row the paper cannot support names what the paper leaves out (`missing`); it is reported
in its own section and not counted in the score.

One module per scene (`rubber12`, `fingertip`, `capacitive6x6`, `ert`, `taxels`) registers its rows
with `register`; `registration(scene, number)` is None for a row not registered yet, which the bench
refuses to measure (runs/fidelity/observations.py `run_checks`).
"""
from dataclasses import dataclass


@dataclass(frozen=True)
class Registration:
    scene: str
    number: str
    quote: str           # the paper's own words (or table), with where they stand
    statistic: str       # what is measured on the scene
    tolerance: str       # when the row holds: the text every measurement of the row is judged by
    missing: str = ""    # not empty: the paper cannot support the row; what it leaves out

    @property
    def supported(self) -> bool:
        return not self.missing


REGISTRY: dict[tuple[str, str], Registration] = {}


def register(scene: str, number: str, quote: str, statistic: str, tolerance: str, missing: str = "") -> Registration:
    key = (scene, number)
    if key in REGISTRY:
        raise ValueError(f"fidelity row {scene}/{number} is registered twice")
    REGISTRY[key] = Registration(scene, number, quote, statistic, tolerance, missing)
    return REGISTRY[key]


def registration(scene: str, number: str) -> Registration | None:
    _load()
    return REGISTRY.get((scene, number))


def _load() -> None:
    # imported on first use so that each scene's module can import `register` from here
    from runs.fidelity.registered import capacitive6x6, ert, fingertip, rubber12, taxels  # noqa: F401
