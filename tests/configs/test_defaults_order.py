"""The configs do not depend on the order of the defaults list: every group is chosen in one
place (configs/config.yaml, an experiment, the command line), so composing with configs/config.yaml's
defaults list reversed gives the same config. Two layers override others by design and keep their
place in the reversed list: a model's YAML may override the trainer and the extras (its recipe:
model=prcnn trains with trainer=reference), so those two stay before model; experiments and the
hyper-parameter search stay last (`@package _global_`, `override /group: ...`)."""
import shutil
from functools import cache
from pathlib import Path

import pytest
import yaml
from hydra import compose, initialize_config_dir
from omegaconf import OmegaConf
from omegaconf.errors import InterpolationResolutionError

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
OVERRIDE_LAYER = ("experiment", "hparams_search")
MODEL_OVERRIDES = ("trainer", "extras")   # what a model's YAML may override
MODELS = sorted(p.stem for p in (CONFIGS / "model").glob("*.yaml"))
EXPERIMENTS = sorted(p.stem for p in (CONFIGS / "experiment").glob("*.yaml"))
# the configurations an experiment sweeps (experiment/<name>/*.yaml), each inside its experiment
CONFIGURATIONS = [(f"experiment={folder.name}", f"+experiment/{folder.name}={path.stem}")
                  for folder in sorted((CONFIGS / "experiment").iterdir()) if folder.is_dir()
                  for path in sorted(folder.glob("*.yaml"))]
# the trainer and extras each of these runs with: the defaults (trainer=default, extras=quick) or
# what the model's YAML overrides them with, unless an experiment or the command line says otherwise
CHOSEN = {(): ("blend", "spread"),
          ("model=blend",): ("blend", "thorough"),
          ("model=resmlp",): ("default", "quick"),
          ("model=extra_trees",): ("default", "quick"),
          ("model=knn",): ("default", "quick"),                 # a library estimator: its YAML alone
          ("model=prcnn",): ("reference", "quick"),
          ("model=lstm_fcn",): ("reference", "quick"),
          ("model=prcnn", "trainer=tsc", "extras=thorough"): ("tsc", "thorough"),
          ("model=blend", "trainer=default", "extras=quick"): ("default", "quick"),
          ("experiment=materials10",): ("tsc", "thorough"),
          ("experiment=materials10", "model=rescnn"): ("tsc", "thorough"),
          ("experiment=materials10", "trainer=reference", "extras=quick"): ("reference", "quick"),
          ("experiment=capacitive_force", "model=resmlp"): ("default", "thorough"),
          ("experiment=tsc_accuracy_vs_time", "+experiment/tsc_accuracy_vs_time=lstm_fcn"): ("tsc", "thorough"),
          ("experiment=accuracy_vs_time", "+experiment/accuracy_vs_time=blend_k3"): ("blend", "thorough"),
          ("hparams_search=resmlp_optuna",): ("default", "quick")}
CASES = list(dict.fromkeys([()] + [(f"model={m}",) for m in MODELS] + [(f"experiment={e}",) for e in EXPERIMENTS]
                           + CONFIGURATIONS + list(CHOSEN)))
HYDRA_KEYS = ("mode", "run", "sweep", "sweeper", "launcher", "callbacks")  # what a run reads of the hydra node


@pytest.fixture(scope="module")
def reversed_configs(tmp_path_factory) -> Path:
    """A copy of configs/ whose config.yaml lists its groups in the opposite order."""
    copy = tmp_path_factory.mktemp("reversed") / "configs"
    shutil.copytree(CONFIGS, copy)
    primary = yaml.safe_load((copy / "config.yaml").read_text())
    def named(*names):
        return [e for e in primary["defaults"] if isinstance(e, dict) and next(iter(e)) in names]
    layer, overridden, model = named(*OVERRIDE_LAYER), named(*MODEL_OVERRIDES), named("model")
    groups = [e for e in primary["defaults"] if e not in layer + overridden]
    assert len(groups) > 2 and layer and len(overridden) == 2 and model, primary["defaults"]
    reversed_groups = groups[::-1]
    at = reversed_groups.index(model[0])
    primary["defaults"] = reversed_groups[:at] + overridden[::-1] + reversed_groups[at:] + layer
    (copy / "config.yaml").write_text(yaml.safe_dump(primary, sort_keys=False))
    return copy


@cache
def composed(config_dir: Path, overrides: tuple) -> dict:
    """The choices, the resolved config (hydra's run settings aside) and what a run reads of the
    hydra node; a config that cannot be resolved (a time-series experiment with model=blend, which
    reads data.n_folds) is its error message, which must then be the same both ways."""
    with initialize_config_dir(config_dir=str(config_dir), version_base="1.3"):
        cfg = compose(config_name="config", overrides=list(overrides), return_hydra_config=True)
    hydra = {key: value for key, value in OmegaConf.to_container(cfg.hydra).items() if key in HYDRA_KEYS}
    choices = OmegaConf.to_container(cfg.hydra.runtime.choices)
    OmegaConf.set_struct(cfg, False)
    del cfg["hydra"]
    try:
        body = OmegaConf.to_container(cfg, resolve=True)
    except InterpolationResolutionError as error:
        body = f"unresolvable: {str(error).splitlines()[0]}"
    return {"choices": choices, "config": body, "hydra": hydra}


def assert_order_free(overrides: tuple, reversed_configs: Path) -> None:
    as_listed, reversed_ = composed(CONFIGS, overrides), composed(reversed_configs, overrides)
    for part in ("choices", "config", "hydra"):
        assert as_listed[part] == reversed_[part], (part, _differences(as_listed[part], reversed_[part]))


def _differences(a, b, path="") -> list[str]:
    if isinstance(a, dict) and isinstance(b, dict):
        return [d for key in sorted(set(a) | set(b), key=str)
                for d in _differences(a.get(key, "<absent>"), b.get(key, "<absent>"), f"{path}.{key}")]
    return [] if a == b else [f"{path}: {a!r} as listed, {b!r} reversed"]


@pytest.mark.parametrize("overrides", CASES, ids=lambda o: " ".join(o) or "default")
def test_the_composed_config_does_not_depend_on_the_order_of_the_defaults(overrides, reversed_configs):
    assert not isinstance(composed(CONFIGS, overrides)["config"], str)  # these all resolve
    assert_order_free(overrides, reversed_configs)


@pytest.mark.slow
@pytest.mark.parametrize("experiment", EXPERIMENTS)
def test_every_experiment_with_every_model_does_not_depend_on_the_order(experiment, reversed_configs):
    for model in MODELS:
        assert_order_free((f"experiment={experiment}", f"model={model}"), reversed_configs)


@pytest.mark.parametrize("overrides, trainer_extras", CHOSEN.items(), ids=lambda o: " ".join(o) or "default")
def test_the_trainer_and_extras_come_from_the_model_the_experiment_or_the_command_line(overrides, trainer_extras):
    choices = composed(CONFIGS, overrides)["choices"]
    assert (choices["trainer"], choices["extras"]) == trainer_extras


def test_model_configs_configure_the_model_and_at_most_its_trainer_and_extras():
    """A model file writes nowhere but under `model`: its defaults name model/ files, or override
    the trainer or the extras it trains with (`override /trainer@_global_.trainer: reference`);
    model=blend, which only regresses, also names the classifier a class-label table trains."""
    allowed = tuple(f"override /{group}@_global_.{group}" for group in MODEL_OVERRIDES)
    offending = []
    for path in sorted((CONFIGS / "model").rglob("*.yaml")):
        text = path.read_text()
        if "@package" in text.splitlines()[0]:
            offending.append(f"{path.name}: {text.splitlines()[0]}")
        for entry in (yaml.safe_load(text) or {}).get("defaults", []):
            name = entry if isinstance(entry, str) else next(iter(entry))
            if name in allowed or (path.name == "blend.yaml" and name == "extra_trees@_global_.classifier"):
                continue
            if name.startswith(("override ", "/")) or "@_global_" in name:
                offending.append(f"{path.name}: {entry}")
    assert not offending, offending
