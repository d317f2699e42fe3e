"""The pre-registered fidelity rows stay frozen: a tolerance changes only with a new quote, every
registered row still exists, and a row the paper cannot support is reported apart."""
import hashlib

import pytest

from runs.fidelity.observations import Measured, Row, markdown, run_checks, verdict
from runs.fidelity.registered import REGISTRY, _load, register, registration

# (quote, tolerance) digests as registered on 2026-12-06 (issue 42; capacitive6x6, ert and taxels's
# supported rows the same day, after rubber12's and fingertip's). A tolerance whose digest
# differs must come with a quote whose digest differs too; then update the pair here.
FROZEN = {
    "capacitive6x6/1": ("85118e7b0485", "5d961a47ba6e"),
    "capacitive6x6/2": ("250685ccf64d", "9bdc0fd745fe"),
    "capacitive6x6/3": ("0a31cfa60cc9", "e6a47585509b"),
    "capacitive6x6/4a": ("0c23fb39c051", "34ff44deabd0"),
    "capacitive6x6/4b": ("6cf8e0b8d3d3", "b93b428b5e81"),
    "capacitive6x6/5": ("579fb6720a13", "2fef02af9c2c"),
    "capacitive6x6/6": ("468fd9c86071", "2050615d0f29"),
    "ert/1": ("c92f7d4c5ea7", "5dc008c01135"),
    "ert/2": ("9e47a7a0dc1c", "1811c74f0534"),
    "ert/3": ("9adfae072f86", "f7671f819924"),
    "ert/4": ("0a33386c561d", "cee765097004"),
    "ert/5": ("b1f3d71dddf4", "43774cbda9f4"),
    "ert/6": ("0d601e3599bf", "f1b0e9a67636"),
    "ert/7": ("7d3fd351fdd8", "7fda8efd95ee"),
    "fingertip/1": ("8876ef92c0d7", "9a55afc6ef6d"),
    "fingertip/2": ("3847f52f8bdc", "5d353bd03a2c"),
    "fingertip/3": ("62b770828c1f", "4ba4e3cb265b"),
    "fingertip/4": ("fb211c953b2d", "6d64efe4a3c3"),
    "fingertip/5": ("833a1c23e659", "80c4903065d8"),
    "fingertip/6": ("b8cbd0cc7e05", "e1f760b22367"),
    "rubber12/1": ("03a593d3de11", "cf7a7845f39a"),
    "rubber12/2": ("b63c41ece5fb", "889cf0e191f3"),
    "rubber12/3a": ("2213150911ed", "98d157dc2954"),
    "rubber12/3b": ("2c58d38ddf89", "3627ad09364d"),
    "rubber12/4": ("8c4fb43fb0cf", "c3752037f912"),
    "rubber12/5": ("da79adf92188", "7094527ceb7e"),
    "rubber12/6": ("8c7a2628c59e", "a91be678fa21"),
    "rubber12/7": ("8626eb63a701", "02c8f17db53a"),
    "rubber12/8": ("b76452e9dc58", "7b350a047f9d"),
    "rubber12/9": ("50633a0716fd", "02c8f17db53a"),
    "rubber12/10": ("8f320bd7e2f4", "b0b4ba2b27d3"),
    "rubber12/11": ("32976ad7ea0e", "0f370a36197a"),
    "rubber12/12": ("221aa2fb93a3", "6a857c171f96"),
    "rubber12/13": ("2eab867b3374", "df903838b8b4"),
    "taxels/1": ("f9768d371d61", "af64996c767c"),
    "taxels/2": ("a70986401fdf", "6cc46bcbbef1"),
    "taxels/3": ("bddcbde5abe0", "62c573a8750a"),
    "taxels/4": ("95145256e6df", "7f0c6882e0a9"),
    "taxels/5": ("98dd6c215322", "815b525adaad"),
    "taxels/6": ("d70bbed4fafb", "bada0fb05e4d"),
}


def digest(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def registered():
    _load()
    return {f"{scene}/{number}": row for (scene, number), row in REGISTRY.items()}


def test_no_tolerance_changed_without_a_new_quote():
    for name, row in registered().items():
        if name not in FROZEN:
            continue
        quote, tolerance = FROZEN[name]
        if digest(row.tolerance) != tolerance:
            assert digest(row.quote) != quote, f"{name}: tolerance changed without a new quote"


def test_every_frozen_row_is_still_registered_with_a_quote_and_a_statistic():
    rows = registered()
    assert set(FROZEN) <= set(rows)
    for name, row in rows.items():
        assert row.quote and row.statistic, name
        assert name in FROZEN, f"{name}: register its digests in FROZEN"


def test_every_row_of_every_scene_is_registered():
    from runs.fidelity.observations import CHECKS, load_scene
    rows = registered()
    for scene in CHECKS:
        assert load_scene(scene), scene
        numbers = {fn.observation[1] for fn in CHECKS[scene]}
        assert numbers, scene
        assert {f"{scene}/{n}" for n in numbers} <= set(rows), f"{scene}: a row without a registration"


def test_an_unregistered_row_is_refused(monkeypatch):
    from runs.fidelity import observations
    calls = []

    def check(probe):
        calls.append(probe)
        return Measured("1", True, "anything")
    check.observation = ("taxels", "99", "statement", "—")
    monkeypatch.setitem(observations.CHECKS, "taxels", [check])
    with pytest.raises(RuntimeError, match="not registered"):
        run_checks("taxels", None)
    assert not calls, "an unregistered row must be refused before it is measured"


def test_a_row_is_registered_once():
    _load()
    with pytest.raises(ValueError, match="registered twice"):
        register("rubber12", "1", "q", "s", "t")


def test_rows_the_papers_cannot_support_name_what_is_missing():
    unsupported = {name for name, row in registered().items() if not row.supported}
    assert unsupported == {"rubber12/4", "rubber12/5", "capacitive6x6/5", "ert/2", "ert/3"}
    assert "Figs. 2-3" in registration("rubber12", "4").missing


def test_a_check_judged_by_another_tolerance_is_refused(monkeypatch):
    from runs.fidelity import observations

    def check(probe):
        return Measured("3 %", True, "CV >= 10 % at every depth")
    check.observation = ("rubber12", "3a", "statement", "—")
    monkeypatch.setitem(observations.CHECKS, "rubber12", [check])
    with pytest.raises(RuntimeError, match="registered tolerance"):
        run_checks("rubber12", None)


def test_an_unsupported_row_has_its_own_verdict(monkeypatch):
    from runs.fidelity import observations

    def check(probe):
        return Measured("P5 smallest", False, "P5 largest of P1-P9 in both, on the mean and at every seed")
    check.observation = ("rubber12", "5", "statement", "—")
    monkeypatch.setitem(observations.CHECKS, "rubber12", [check])
    [row] = run_checks("rubber12", None)
    assert verdict(row.measured) == "not supported by the paper"
    assert "not supported by the paper" in markdown([row])
    assert verdict(Measured("x", False)) == "does not hold"
    assert isinstance(row, Row)
