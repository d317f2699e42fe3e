"""The README and docs/ name files of this repository (`runs/report/metrics_file.py`,
`configs/experiment/accuracy_vs_time/`, [links](docs/fidelity.md#fingertip)) and modules to run
(`python -m common.run_status`): every one must exist, so a page cannot silently go stale when
code moves. A path is a token whose first part is a top-level entry git tracks (`runs/...`,
`configs/...`, `.ci/run`); a placeholder in it (`configs/scene/base/<sensor>.yaml`,
`data/scenes/*_effects.py`) must match at least one file. Run artefacts (`metrics.json`,
`outputs/...`, `<run dir>/model.onnx`) are not repository paths and are not checked."""
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))
PATH_TOKEN = re.compile(r"[\w.\-/<>*…]+")
LINK = re.compile(r"\]\(([^)\s]+)\)")
MODULE = re.compile(r"python -m ([A-Za-z_][\w.]*)")
EXTERNAL = re.compile(r"^[a-z][a-z0-9+.-]*:")   # https:, mailto:


def tracked_top_level() -> set[str]:
    files = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    return {line.split("/")[0] for line in files.splitlines()}


TOP_LEVEL = tracked_top_level()


def exists(path: str) -> bool:
    """A path (relative to the repository root) exists; one with placeholders matches something;
    one ending in / is a folder."""
    pattern = re.sub(r"<[^>]*>", "*", path).replace("…", "*")
    if "*" in pattern:
        return any(ROOT.glob(pattern.rstrip("/")))
    target = ROOT / path
    return target.is_dir() if path.endswith("/") else target.exists()


def repository_paths(text: str) -> set[str]:
    """Every token of `text` that names a path under a tracked top-level entry."""
    paths = set()
    for token in PATH_TOKEN.findall(text):
        token = token.removeprefix("./").rstrip(".")
        if "/" in token and token.split("/")[0] in TOP_LEVEL:
            paths.add(token)
    return paths


def heading_anchors(page: Path) -> set[str]:
    """GitHub's anchors for a page's headings: lower case, punctuation dropped, spaces to hyphens."""
    anchors = set()
    for line in page.read_text().splitlines():
        if line.startswith("#"):
            title = line.lstrip("#").strip().lower()
            anchors.add(re.sub(r"[^\w\- ]", "", title).replace(" ", "-"))
    return anchors


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_repository_path_a_page_names_exists(page):
    text = re.sub(r"<!--.*?-->", "", page.read_text())       # a generated block's marker names a table, not a path
    missing = sorted(path for path in repository_paths(text) if not exists(path))
    assert not missing, f"{page.relative_to(ROOT)} names paths that do not exist: {missing}"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_link_of_a_page_leads_somewhere(page):
    broken = []
    for target in LINK.findall(page.read_text()):
        if EXTERNAL.match(target):
            continue
        path, _, anchor = target.partition("#")
        resolved = (page.parent / path).resolve() if path else page
        if not resolved.exists():
            broken.append(target)
        elif anchor and resolved.suffix == ".md" and anchor not in heading_anchors(resolved):
            broken.append(f"{target} (no such heading)")
    assert not broken, f"{page.relative_to(ROOT)} links to: {broken}"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_module_a_page_runs_exists(page):
    missing = [name for name in MODULE.findall(page.read_text())
               if name != "pytest" and not ((ROOT / name.replace(".", "/")).with_suffix(".py").is_file())]
    assert not missing, f"{page.relative_to(ROOT)} runs modules that do not exist: {missing}"


def test_the_checks_catch_a_stale_page(tmp_path):
    """The checks fail on what they are for: a moved file, a missing folder, a broken link or
    anchor, a module that is gone; and pass what exists."""
    assert repository_paths("see `runs/report/metrics_file.py` and runs/report/") == {
        "runs/report/metrics_file.py", "runs/report/"}
    assert not exists("runs/report/pipeline.pkl") and not exists("configs/variant/")
    assert not exists("configs/variant/<name>.yaml") and exists("configs/scene/base/<sensor>.yaml")
    assert repository_paths("`outputs/<run>/model.onnx`, `metrics.json`, `.venv/bin/python`") == set()
    page = tmp_path / "page.md"
    page.write_text("# Top heading\n\n## The eager twin: pipeline.npz\n")
    assert {"top-heading", "the-eager-twin-pipelinenpz"} <= heading_anchors(page)
    assert MODULE.findall("python -m runs.report.pareto <sweep dir>") == ["runs.report.pareto"]


# ---- generated tables (docs/generate.py, docs/tables.py) -----------------------------------------
# Every table of measured numbers is rendered from results/*.jsonl; a page whose generated block
# differs from what its records render, or that cites a record that is missing, fails here.

from common import result_records  # noqa: E402
from common.result_records import RecordError, recording  # noqa: E402
from docs import generate  # noqa: E402

PLUS_MINUS_OUTSIDE_BLOCKS = 50    # issue 39's budget for hand-typed "±" across README + docs/


def outside_blocks(text: str, page: Path) -> str:
    pieces, position = [], 0
    for _, start, end in generate.blocks(text, page):
        pieces.append(text[position:start])
        position = end
    return "".join(pieces) + text[position:]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_generated_blocks_are_what_the_records_render(page):
    assert generate.render_page(page) == page.read_text(), (
        f"{page.relative_to(ROOT)}: a generated block differs from what results/ renders: run `make docs`")


def test_hand_typed_spreads_stay_within_the_budget():
    counts = {page.name: outside_blocks(page.read_text(), page).count("±") for page in PAGES}
    assert sum(counts.values()) <= PLUS_MINUS_OUTSIDE_BLOCKS, counts


def test_every_table_renders_from_the_committed_records():
    cited = {name for page in PAGES for name, _, _ in generate.blocks(page.read_text(), page)}
    assert cited, "no page has a generated block"
    for name in sorted(cited):
        text, records = generate.TABLES[name]()
        assert records and "|" in text, name


@pytest.mark.parametrize("edit, message", [
    (lambda text: text.replace(generate.END, "", 1), "has no '<!-- end generated -->'"),
    (lambda text: text.replace("<!-- generated: readme/tour -->", "", 1), "without its opening marker"),
    (lambda text: text.replace("<!-- generated: readme/tour -->", "<!-- generated: readme/tours -->", 1),
     "block 'readme/tours' names no table"),
])
def test_hand_edited_markers_stop_the_generator(tmp_path, monkeypatch, capsys, edit, message):
    page = tmp_path / "README.md"
    page.write_text(edit((ROOT / "README.md").read_text()))
    monkeypatch.setattr(generate, "PAGES", [page])
    assert generate.main([]) == 2
    error = capsys.readouterr().err.strip()
    assert message in error and "README.md" in error and "\n" not in error
    assert page.read_text() == edit((ROOT / "README.md").read_text())       # nothing written


def test_a_corrupt_or_missing_record_stops_the_generator(tmp_path, monkeypatch, capsys):
    results = tmp_path / "results"
    results.mkdir()
    for source in (ROOT / "results").glob("*.jsonl"):
        (results / source.name).write_text(source.read_text())
    monkeypatch.setattr(result_records, "RESULTS", results)
    monkeypatch.setattr(generate, "PAGES", [ROOT / "README.md"])
    tour = results / "quick_tour.jsonl"
    tour.write_text(tour.read_text()[:-40])                   # a truncated last line
    assert generate.main(["--check"]) == 2
    assert "quick_tour.jsonl:" in capsys.readouterr().err
    tour.unlink()
    assert generate.main(["--check"]) == 2
    assert "quick_tour.jsonl: no such results file" in capsys.readouterr().err


def test_a_table_says_stale_when_its_measured_code_changes(tmp_path, monkeypatch):
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "forest.py").write_text("DEPTH = 3\n")
    monkeypatch.setattr(result_records, "ROOT", tmp_path)
    monkeypatch.setattr(result_records, "RESULTS", tmp_path / "results")
    monkeypatch.setattr(result_records, "LOCK", ROOT / "requirements.lock")
    with recording("forest", ["models/"], command="python bench/forest.py") as record:
        record.add("scores", {"value": 1})
    stored = result_records.latest("forest", "scores")
    assert "stale" not in generate.provenance([stored]) and "python bench/forest.py" in generate.provenance([stored])
    (tmp_path / "models" / "forest.py").write_text("DEPTH = 4\n")
    assert "**stale**: models/ changed" in generate.provenance([stored])
    with pytest.raises(RecordError):
        result_records.latest("forest", "latency")
