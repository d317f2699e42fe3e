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

ROOT = Path(__file__).resolve().parents[1]
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
    missing = sorted(path for path in repository_paths(page.read_text()) if not exists(path))
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
