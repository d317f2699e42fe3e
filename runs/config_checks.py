"""Config mistakes found before anything heavy is imported, so a typo costs a second, not a start-up.

Hydra already refuses unknown groups, options and keys of the composed config. What it cannot see:
- a key added with `+` (`+scene.sparkle=1`) that the component's constructor does not take: it
  would surface only when the component is built, after torch and friends are loaded, as a
  TypeError. Each `_target_` of ours is looked up in its source file with `ast` (no import:
  runs/target_signatures.py) and the node's keys are checked against its parameters;
- a value of the wrong type or out of range (`seed=abc`, `trainer.max_epochs=1.5`,
  `trainer.batch_size=0`): it would surface deep inside numpy or torch as a traceback. The
  settings in SETTINGS and TRAINER are checked by their rule; every parameter of one of our
  `_target_`s by the rule of its name in PARAMETERS, else by its annotation, else by the type of
  its default (an int default takes integers, a float default numbers, a bool true or false, a
  str strings, a tuple lists; null is left to the component, which decides what null means).
Targets outside this repository (scikit-learn, torch) and constructors taking **kwargs are left
to instantiation, as are values only a component can judge (a scene's sizes, a file's contents).

`check_config(cfg)` runs every check; train.py calls it on the composed config before start-up,
and runs/run.py on each job's config (sweep jobs are composed by Hydra, after train.py's
check). It also returns a warning for each trainer setting given as an override that no part of
the run reads (trainer.max_epochs with a tree model).
"""
import ast
import math
import re
from dataclasses import dataclass
from pathlib import Path

from omegaconf import DictConfig, OmegaConf
from omegaconf.errors import InterpolationResolutionError

from common.errors import InputError
from common.threads import resolve_threads
from runs.target_signatures import Parameter, module_constant, target_parameters, target_signature

HYDRA_KEYS = {"_target_", "_convert_", "_partial_", "_recursive_", "_args_"}


@dataclass(frozen=True)
class Accepts:
    """What one setting takes: its types (of integer, number, bool, string, list, mapping), a range
    for numbers, the choices for a string, what each list item takes, and whether null is allowed."""
    types: frozenset
    low: float | None = None
    high: float | None = None
    open_low: bool = False
    open_high: bool = False
    choices: tuple = ()
    items: "Accepts | None" = None
    null: bool = False

    def takes(self, value) -> bool:
        if value is None:
            return self.null
        if isinstance(value, bool):
            return "bool" in self.types
        if isinstance(value, (int, float)):
            is_integer = isinstance(value, int)
            if not ("number" in self.types or is_integer and "integer" in self.types):
                return False
            return math.isfinite(value) and self._in_range(value)
        if isinstance(value, str):
            return "string" in self.types and (not self.choices or any(re.fullmatch(c, value) for c in self.choices))
        if isinstance(value, (list, tuple)):
            return "list" in self.types and (self.items is None or all(self.items.takes(v) for v in value))
        if isinstance(value, dict):
            return "mapping" in self.types
        return False

    def _in_range(self, value) -> bool:
        return ((self.low is None or (value > self.low if self.open_low else value >= self.low))
                and (self.high is None or (value < self.high if self.open_high else value <= self.high)))

    def __str__(self) -> str:
        words = []
        for kind in sorted(self.types, key=["integer", "number", "bool", "string", "list", "mapping"].index):
            if kind in ("integer", "number"):
                if kind == "integer" and "number" in self.types:
                    continue  # a number includes the integers
                words.append(f"{'an integer' if kind == 'integer' else 'a number'}{self._range()}")
            elif kind == "bool":
                words.append("true or false")
            elif kind == "string":
                choices = [c.replace(r"\d+", "<n>") for c in self.choices]
                words.append(f"one of {', '.join(choices)}" if choices else "a string")
            elif kind == "list":
                words.append(f"a list of {plural(str(self.items))}" if self.items else "a list")
            else:
                words.append("a mapping")
        return " or ".join(words + ["null"] * self.null)

    def _range(self) -> str:
        low, high = self.low, self.high
        if low is not None and high is not None:
            if not (self.open_low or self.open_high) and self.types == {"integer"}:
                return f" from {low} to {high}"
            return f" in {'(' if self.open_low else '['}{low}, {high}{')' if self.open_high else ']'}"
        if low is not None:
            return f" {'>' if self.open_low else '>='} {low}"
        if high is not None:
            return f" {'<' if self.open_high else '<='} {high}"
        return ""


def plural(description: str) -> str:
    return re.sub(r"^(?:an|a) (\w+)", r"\1s", description)


def integer(low=None, high=None, null=False) -> Accepts:
    return Accepts(frozenset({"integer"}), low=low, high=high, null=null)


def number(low=None, high=None, open_low=False, open_high=False, null=False) -> Accepts:
    return Accepts(frozenset({"number"}), low=low, high=high, open_low=open_low, open_high=open_high, null=null)


def text(*choices, null=False) -> Accepts:
    return Accepts(frozenset({"string"}), choices=tuple(choices), null=null)


FLAG = Accepts(frozenset({"bool"}))
SEED = integer(0, 2 ** 32 - 1)   # numpy's and torch's seed range
FRACTION = number(0, 1, open_low=True, open_high=True)
SHARE = number(0, 1, open_high=True)   # may be 0: that part is not held out


# How nets train (configs/trainer/*.yaml): every key a trainer option may hold.
TRAINER = {
    "max_epochs": integer(1),
    "batch_size": integer(2),   # BatchNorm cannot normalise a batch of one
    "early_stopping_patience": integer(0, null=True),   # null: train every epoch
    "early_stopping_min_patience": integer(0, null=True),   # null: the patience, fixed
    "early_stopping_min_delta": number(0),
    "lr_plateau_patience": integer(0),
    "device": text("cpu", "cuda", r"cuda:\d+", "auto"),
    "progress": FLAG,
    "optimizer": text(*module_constant("models.timeseries_classifier", "OPTIMISERS")),
    "lr": number(0, open_low=True),
    "momentum": number(0, 1, open_high=True),
    "weight_decay": number(0),
    "lr_schedule": text(*module_constant("models.timeseries_classifier", "SCHEDULES")),
    "lr_factor": FRACTION,
    "min_lr": number(0),
    "lr_milestones": Accepts(frozenset({"list"}), items=integer(1)),
    "lr_gamma": number(0, 1, open_low=True),
    "max_batch_fraction": number(0, 1, open_low=True, null=True),
    "recalibrate_batchnorm": FLAG,
    "epoch_selection": text(*module_constant("models.timeseries_classifier", "EPOCH_SELECTIONS")),  # how a net's epochs are chosen
    "n_folds": integer(2),                             # epoch_selection=folds: stratified folds by recording
    "resume_from": text(null=True),
    "checkpoint": FLAG,
}
# The run's own settings (configs/config.yaml and the groups without a _target_). cost.budget_s's
# sign is export/latency.py's to refuse, where the measurement starts.
SETTINGS = {"seed": SEED, "overwrite": FLAG, "cost.budget_s": number(), "cost.measure_latency": FLAG,
            "cost.onnx_latency_calls": integer(0),
            "spread.splits": integer(1), "analysis.ablation": FLAG, "analysis.progress": FLAG, "analysis.identifiability_bins": integer(1),
            "export.enabled": FLAG, "export.opset": integer(1), "export.file": text(), "augment.enabled": FLAG}
# A parameter of one of our targets with one of these names takes these values wherever it
# appears: the trainer's settings reach the nets under their own names, the splits the datamodules.
PARAMETERS = {
    **{name: TRAINER[name] for name in ("max_epochs", "batch_size", "early_stopping_patience",
                                        "early_stopping_min_patience", "early_stopping_min_delta", "lr_plateau_patience",
                                        "device", "progress", "lr", "momentum", "weight_decay", "lr_factor", "min_lr",
                                        "max_batch_fraction")},
    "milestones": TRAINER["lr_milestones"], "gamma": TRAINER["lr_gamma"], "seed": SEED,
    "n_estimators": integer(1), "n_folds": integer(2), "val_fraction": FRACTION, "test_fraction": FRACTION,
    "calibration_fraction": SHARE, "recorded_test_fraction": SHARE, "decimate": integer(1),
    "window_length": integer(1, null=True), "window_step": integer(1, null=True), "trim_start": integer(0),
    "trim_end": integer(0),
}


ANNOTATION_TYPES = {"int": {"integer"}, "float": {"number"}, "bool": {"bool"}, "str": {"string"},
                    "list": {"list"}, "tuple": {"list"}, "Sequence": {"list"}, "dict": {"mapping"},
                    "Mapping": {"mapping"}}


def _annotation_types(node: ast.expr) -> set | None:
    """The types an annotation allows ('None' for null); None when it names anything else."""
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.BitOr):
        left, right = _annotation_types(node.left), _annotation_types(node.right)
        return None if left is None or right is None else left | right
    if isinstance(node, ast.Constant) and node.value is None:
        return {"None"}
    if isinstance(node, ast.Subscript):
        node = node.value
    return set(ANNOTATION_TYPES[node.id]) if isinstance(node, ast.Name) and node.id in ANNOTATION_TYPES else None


def parameter_rule(parameter: Parameter) -> Accepts | None:
    """What a parameter takes: by its annotation, else by the type of its default (null always:
    the component decides what null means); None when neither says."""
    if parameter.annotation is not None:
        types = _annotation_types(parameter.annotation)
        if types:
            return Accepts(frozenset(types - {"None"}), null="None" in types)
        return None
    default = parameter.default
    if isinstance(default, bool):
        return Accepts(frozenset({"bool"}), null=True)
    if isinstance(default, int):
        return integer(null=True)
    if isinstance(default, float):
        return number(null=True)
    if isinstance(default, str):
        return text(null=True)
    if isinstance(default, (list, tuple)):
        numbers = default and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in default)
        return Accepts(frozenset({"list"}), items=number() if numbers else None, null=True)
    return None


# -- the checks --------------------------------------------------------------------------------
def check_value(key: str, value, accepts: Accepts, source: str | None = None) -> None:
    if not accepts.takes(value):
        origin = f" (= {source})" if source else ""
        raise InputError(f"{key}{origin} must be {accepts}, got {value!r}")


def check_settings(config: dict) -> None:
    """The top-level settings, the threads, the trainer's settings and the regression splits, on
    the resolved config as plain containers."""
    resolve_threads(config.get("threads", 1))
    for key, accepts in SETTINGS.items():
        section, _, name = key.rpartition(".")
        node = config.get(section) if section else config
        if isinstance(node, dict) and name in node:
            check_value(key, node[name], accepts)
    for key, value in (config.get("trainer") or {}).items():
        if key == "per_model":  # a model's own recipe beside the common one (trainer/reference.yaml)
            for model, recipe in (value or {}).items():
                for name, setting in recipe.items():
                    check_value(f"trainer.per_model.{model}.{name}", setting,
                                TRAINER.get(name) or _unknown(f"trainer.per_model.{model}", name))
        else:
            check_value(f"trainer.{key}", value, TRAINER.get(key) or _unknown("trainer", key))
    data = config.get("data") or {}
    if str(data.get("_target_", "")).startswith("data.datamodules.regression."):
        # imported here: data/splits/ loads scikit-learn (seconds on a busy machine), which the
        # checks before this one (a misspelt key, a missing file) need not wait for
        from data.splits.settings import check_split_settings
        check_split_settings(data.get("n_folds"), data.get("test_fraction"), data.get("val_fraction"),
                             data.get("calibration_fraction"), data.get("split"))


def _unknown(where: str, key: str):
    raise InputError(f"{where} has no setting '{key}' (valid: {', '.join(TRAINER)})")


def check_target_keys(cfg: DictConfig) -> None:
    """Every node with a `_target_` of ours carries only keys its target takes."""
    def walk(node, where):
        if isinstance(node, dict):
            target = node.get("_target_")
            if isinstance(target, str):
                accepted = target_parameters(target)
                unknown = sorted(set(node) - HYDRA_KEYS - set(accepted or ()))
                if accepted is not None and unknown:
                    raise InputError(f"{where or 'config'} has no parameter '{unknown[0]}' (valid: "
                                     f"{', '.join(accepted)})")
            for key, value in node.items():
                walk(value, f"{where}.{key}" if where else str(key))
        elif isinstance(node, list):
            for index, value in enumerate(node):
                walk(value, f"{where}[{index}]")
    walk(OmegaConf.to_container(cfg, resolve=False), "")


def check_target_values(raw: dict, config: dict) -> None:
    """Every parameter of a target of ours holds a value of the type and range it takes (`raw`:
    the config before interpolation, `config`: after). A node that is a reference to another
    (data.source: ${scene}) is checked where it lives."""
    def walk(raw, value, where):
        if isinstance(raw, str) and "${" in raw:
            return  # interpolated from elsewhere: checked under its own name
        if isinstance(value, dict):
            target = value.get("_target_")
            signature = target_signature(target) if isinstance(target, str) else None
            for parameter in signature[0] if signature else ():
                accepts = PARAMETERS.get(parameter.name) or parameter_rule(parameter)
                if parameter.name in value and accepts is not None:
                    source = raw.get(parameter.name) if isinstance(raw, dict) else None
                    check_value(f"{where}.{parameter.name}", value[parameter.name], accepts,
                                source if isinstance(source, str) and "${" in source else None)
            for key, item in value.items():
                walk(raw.get(key) if isinstance(raw, dict) else None, item, f"{where}.{key}" if where else str(key))
        elif isinstance(value, list):
            for index, item in enumerate(value):
                walk(raw[index] if isinstance(raw, list) and index < len(raw) else None, item, f"{where}[{index}]")

    walk(raw, config, "")


def unreached_trainer_settings(raw: dict, config: dict, overrides) -> list[str]:
    """The trainer settings among `overrides` (Hydra's `key=value` strings) that no part of the run
    reads: not interpolated anywhere outside the trainer group, nor read by code (the checkpoint
    settings, which runs/classification.py gives a model that checkpoints)."""
    elsewhere = str({key: value for key, value in raw.items() if key != "trainer"})
    model = str((config.get("model") or {}).get("_target_", "none"))
    checkpoints = "checkpoint_path" in (target_parameters(model) or ())
    given = {}   # key -> the override that sets it last (the one Hydra applies)
    for override in overrides:
        key = override.lstrip("+").split("=", 1)[0]
        if not override.startswith("~") and key.startswith("trainer."):
            given[key] = override.lstrip("+")
    unread = []
    for key, override in given.items():
        parts = key.split(".")
        read = re.search(rf"(?<![\w.]){re.escape(key)}(?!\w)", elsewhere) or any(  # the key or its node
            re.search(rf"(?<![\w.]){re.escape('.'.join(parts[:n]))}(?![\w.])", elsewhere) for n in range(1, len(parts)))
        if not read and not (checkpoints and key in ("trainer.checkpoint", "trainer.resume_from")):
            unread.append(override)
    if not unread:
        return []
    return [f"{', '.join(unread)}: no part of this run reads {'it' if len(unread) == 1 else 'them'} "
            f"(model: {model.rpartition('.')[2]}); ignored"]


def check_path_key(cfg: DictConfig) -> None:
    """A file's path is data.path for every source; a recordings source is given it by
    data/datamodules/recording_files.py, so a value set at the older data.source.path is refused."""
    source = OmegaConf.select(cfg, "data.source", default=None)
    value = source.get("path") if isinstance(source, DictConfig) else None
    if value is not None:
        raise InputError(f"data.source.path is not a setting: a file's path is data.path for every data source "
                         f"(data.path={value})")


def check_data_path(cfg: DictConfig) -> None:
    """data.path names a file that exists: said before torch is imported and before Hydra makes a
    run folder (the readers say the same, later, for a file that went away in between)."""
    data = OmegaConf.select(cfg, "data", default=None)
    if not isinstance(data, DictConfig) or "path" not in data or OmegaConf.is_missing(data, "path"):
        return
    path = data.path
    if isinstance(path, str) and path and not Path(path).is_file():
        raise InputError(f"{path}: no such file (data.path)")


TIME_SERIES_DATA = ("data.datamodules.timeseries.TimeSeriesDataModule",
                    "data.datamodules.recording_files.from_recordings_file")
TABLE_ONLY_MODEL = "models.weighted_blend.ValidationWeightedBlend"


def check_model_fits_data(cfg: DictConfig) -> None:
    """model=blend learns from one row per press; recordings need a model over windows. Said
    before composing the rest, whose first symptom would be a key the blend reads from table data
    (data.n_folds)."""
    data_target = OmegaConf.select(cfg, "data._target_", default=None)
    model_target = OmegaConf.select(cfg, "model._target_", default=None)
    if data_target in TIME_SERIES_DATA and model_target == TABLE_ONLY_MODEL:
        raise InputError("model=blend learns from tables, one row per press; recordings train a time-series "
                         "model: leave model= out (model=auto chooses one on validation) or name one (model=prcnn, "
                         "rescnn, inceptiontime, lstm_fcn)")


def check_config(cfg: DictConfig, overrides=()) -> list[str]:
    """Every check above on a composed config: raises InputError naming the first wrong setting
    (its key, its value and what it takes); returns one warning line when trainer settings among
    `overrides` reach nothing in this run (an empty list otherwise)."""
    run_config = OmegaConf.masked_copy(cfg, [key for key in cfg if key != "hydra"])
    check_path_key(run_config)
    check_data_path(run_config)
    check_model_fits_data(run_config)
    try:
        missing = sorted(OmegaConf.missing_keys(run_config))
        if missing:
            raise InputError(f"{missing[0]} needs a value (add {missing[0]}=...)")
        config = OmegaConf.to_container(run_config, resolve=True)
    except InterpolationResolutionError as error:  # e.g. model=blend reads data.n_folds, which time-series data lacks
        raise InputError(f"{error.full_key}: {str(error).splitlines()[0]}") from None
    raw = OmegaConf.to_container(run_config, resolve=False)
    check_settings(config)
    check_target_keys(run_config)
    check_target_values(raw, config)
    return unreached_trainer_settings(raw, config, overrides)
