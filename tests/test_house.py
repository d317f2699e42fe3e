"""The house rules: every module imports, each floor (common -> data -> models -> export -> runs)
imports only the floors below it, and every config file composes."""
import ast
import importlib
from pathlib import Path

import pytest
from hydra import compose, initialize_config_dir
from hydra.utils import get_object
from omegaconf import OmegaConf

from runs.config_checks import check_target_keys

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("common", "data", "models", "export", "runs")
# The floors, lowest first: common/ (errors, atomic writes, progress, threads, run status) ->
# data/ -> models/ (estimators and nets) -> export/ (ONNX) -> runs/ (what a run or study does,
# its report) -> train.py, predict.py. A floor imports only floors below it; bench/ measures the
# library and nothing imports it (tests call the library's measurement functions, not bench/).
FORBIDDEN = {"common": {"data", "models", "export", "runs"}, "data": {"models", "export", "runs"},
             "models": {"export", "runs"}, "export": {"runs"}, "runs": set()}
ENTRY_POINTS = {"train", "predict"}


def modules(root: Path = ROOT) -> list[str]:
    return sorted(".".join(p.relative_to(root).with_suffix("").parts).removesuffix(".__init__")
                  for package in PACKAGES for p in (root / package).rglob("*.py"))


def imported_roots(module: str, root: Path = ROOT) -> set[str]:
    """Top-level names of everything `module` imports (absolute imports only: the house uses no others)."""
    path = root / (module.replace(".", "/") + ".py")
    if not path.is_file():
        path = root / module.replace(".", "/") / "__init__.py"
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names |= {alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0, f"{module} uses a relative import"
            names.add(node.module.split(".")[0])
    return names


@pytest.mark.parametrize("module", modules())
def test_every_module_imports(module):
    assert importlib.import_module(module).__name__ == module


def floor_violations(root: Path) -> list[str]:
    """'<module> imports <name>' for every import in the tree at `root` that breaks the floors."""
    violations = []
    for module in modules(root):
        package = module.split(".")[0]
        bad = imported_roots(module, root) & (FORBIDDEN[package] | ENTRY_POINTS | {"bench"})
        violations += [f"{module} imports {name}" for name in sorted(bad)]
    # docs/ (the generator of the pages' tables) reads result records only: no model, no run.
    for script, forbidden in (("bench", ENTRY_POINTS), ("tests", ENTRY_POINTS | {"bench"}),
                              ("docs", ENTRY_POINTS | {"bench", "data", "models", "export", "runs"})):
        for path in (root / script).rglob("*.py"):
            if any(part.startswith(".") for part in path.relative_to(root).parts):  # bench/.venv-aeon: the peer's venv
                continue
            module = ".".join(path.relative_to(root).with_suffix("").parts)
            violations += [f"{module} imports {name}" for name in sorted(imported_roots(module, root) & forbidden)]
    return violations


def test_imports_flow_one_way():
    violations = floor_violations(ROOT)
    print("\n".join(f"{m}: {sorted(imported_roots(m) & set(PACKAGES))}" for m in modules()))
    assert not violations, violations


def test_the_checker_catches_a_violation(tmp_path):
    """The rule above can fail: in a tree of its own (the source tree is left alone), a data module
    that imports models and a test that imports bench are reported, and nothing else."""
    for relative, source in (("data/_house_probe.py", "from models.trees import TreeRegressor\n"),
                             ("models/trees.py", "import numpy as np\n"),
                             ("tests/test_probe.py", "import bench.fidelity\n")):
        (tmp_path / relative).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / relative).write_text(source)
    assert floor_violations(tmp_path) == ["data._house_probe imports models", "tests.test_probe imports bench"]


# Options that only make sense in a time-series run compose inside one (experiment=materials10
# sets the fingertip scene, the time-series data, PR-CNN and the time-series trainer).
TIME_SERIES = {"model": {"prcnn", "rescnn", "inceptiontime", "lstm_fcn"},
               "data": {"timeseries", "fingertip", "base/timeseries", "recordings_npz", "recordings_table"},
               "scene": {"fingertip", "fingertip_minimal", "base/fingertip"},
               "trainer": {"tsc"}, "augment": {"virtual_force_levels"}, "size": {"paper"}}
# model/base/*: what models share, composed through every model that inherits it (base/kfold has
# no estimator of its own)
MODEL_BASES = {"base/kfold", "base/tree", "base/timeseries_classifier"}


def config_choices() -> list[list[str]]:
    """One override list per config file: every option of every group (bases included, the model's
    aside), every experiment, the configurations an experiment sweeps (experiment/<name>/*.yaml,
    inside that experiment), every size, and the launchers."""
    configs = ROOT / "configs"
    choices = []
    for path in sorted(configs.rglob("*.yaml")):
        relative = path.relative_to(configs).with_suffix("")
        parts = relative.parts
        if len(parts) == 1 or parts[0] == "hydra" and parts[1] != "launcher":
            continue
        if parts[0] == "hydra":
            choices.append([f"hydra/launcher={parts[-1]}"])  # covers launcher/<name>
            continue
        group, option = parts[0], "/".join(parts[1:])
        if group == "model" and option in MODEL_BASES:
            continue
        if group == "experiment" and len(parts) == 3:
            choices.append([f"experiment={parts[1]}", f"+experiment/{parts[1]}={parts[2]}"])
            continue
        prefix = "+" if group == "size" else ""
        context = ["experiment=materials10"] if option in TIME_SERIES.get(group, ()) else []
        choices.append(context + [f"{prefix}{group}={option}"])
    return choices


@pytest.mark.parametrize("overrides", config_choices(), ids=lambda o: " ".join(o))
def test_every_config_file_composes(overrides):
    with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
        cfg = compose(config_name="config", overrides=overrides, return_hydra_config=True)
    choices = cfg.hydra.runtime.choices
    for override in overrides:  # the option asked for is the one composed
        group, option = override.lstrip("+").split("=", 1)
        assert choices[group] == option, (group, choices.get(group))
    check_target_keys(cfg)  # every key of a node with a _target_ of ours is a parameter it takes
    # resolve what a run reads, interpolations included, and every _target_ must import
    targets = []
    for key in ("data", "model", "scene", "trainer", "logger"):
        if key in cfg:
            targets += list(_targets(OmegaConf.to_container(cfg[key], resolve=True, throw_on_missing=False)))
    for target in targets:
        assert callable(get_object(target)), target


def _targets(node):
    if isinstance(node, dict):
        if isinstance(node.get("_target_"), str):
            yield node["_target_"]
        for value in node.values():
            yield from _targets(value)
    elif isinstance(node, list):
        for value in node:
            yield from _targets(value)


def test_every_yaml_is_reached_by_the_composition_test():
    # an override names a file by its group below the top-level one and its option:
    # model=resmlp -> resmlp, hydra/launcher=slurm -> launcher/slurm, +experiment/e=x -> e/x
    covered = {"/".join(key.lstrip("+").split("/")[1:] + [option])
               for choice in config_choices() for key, option in (o.split("=", 1) for o in choice)}
    configs = ROOT / "configs"
    files = {"/".join(p.relative_to(configs).with_suffix("").parts[1:]) for p in configs.rglob("*.yaml")
             if p.parent != configs and p.relative_to(configs).parts[:2] != ("hydra", "default.yaml")}
    files -= MODEL_BASES
    assert files <= covered, files - covered
