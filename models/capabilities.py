"""What a model offers, declared by the model as a scikit-learn tag, so runs/ and export/ read a
declaration instead of probing for attributes or switching on classes.

scikit-learn declares what an estimator can do in `__sklearn_tags__` (a `Tags` dataclass); ours
extend it with one more field, `touchstone`, holding the Capabilities below. Touchstone's
estimators declare them through models/estimator_base.py. An estimator that declares nothing
(a library one named by `_target_` in a model config, e.g. sklearn.neighbors.KNeighborsRegressor)
gets LIBRARY: a plain `fit(X, y)`, predictions and nothing beyond, exported through skl2onnx's
own converters, its fitted state not stored (model.onnx is what such a run deploys).
"""
from dataclasses import dataclass, field, fields, replace

from sklearn.utils import Tags, get_tags

SIZES = ("n_parameters", "n_nodes")
NAMES = ("class", "kind", "network")


@dataclass(frozen=True)
class Capabilities:
    # fit(X, y, X_val, y_val, epoch_callback, groups) (models/estimator_base.py); else fit(X, y)
    shared_fit: bool = False
    # predict_std(X) -> (mean, sigma) and calibrate(X, y) -> conformal intervals (models/uncertainty.py)
    intervals: bool = False
    # importances() -> (what they belong to, one value per feature) or None
    importances: bool = False
    # K copies fitted (K-fold or seeds): fold_fit_time_s_, fold_fit_cpu_time_s_, fold_warning_
    fold_costs: bool = False
    # named candidates weighted per target: models_, weights_, selected_(), the selection report
    weighs_candidates: bool = False
    # fits candidates and deploys the one chosen on validation (chosen_model_, report())
    chooses: bool = False
    # trained for epochs: best_epoch_, n_epochs_, batch_size_, epoch_selection
    epochs: bool = False
    # scores itself on held-out predictions of every training window (out_of_fold_proba_), so it
    # may train on the validation recordings too
    holds_out_training: bool = False
    # calibrate(X, y) fits a temperature to its class probabilities
    calibrates_probabilities: bool = False
    # takes windows of recordings (n, channels, steps), not table rows
    reads_windows: bool = False
    # classifier(): the classifier of the same kind and settings (a tree regressor on a class label)
    has_classifier: bool = False
    # the fitted attribute (without its trailing _) metrics report as its size
    size: str | None = None
    # metrics' model name: its class, its class and kind ("TableClassifier(mlp)"), or its network's class
    named_by: str = "class"
    # has an ONNX converter (Touchstone's registry, or skl2onnx's for a library estimator)
    onnx_exportable: bool = True
    # its fitted state goes into pipeline.npz (models/fitted_state.py)
    storable: bool = False

    def __post_init__(self):
        if self.size not in (None, *SIZES) or self.named_by not in NAMES:
            raise ValueError(f"capabilities: size must be one of {SIZES} or None and named_by one of {NAMES}")


LIBRARY = Capabilities()


@dataclass(slots=True)
class TouchstoneTags(Tags):
    """scikit-learn's tags and Touchstone's capabilities."""
    touchstone: Capabilities = field(default_factory=Capabilities)


def declare(tags: Tags, **offered) -> TouchstoneTags:
    """`tags` (from super().__sklearn_tags__()) with these capabilities set on top of any declared."""
    declared = tags.touchstone if isinstance(tags, TouchstoneTags) else LIBRARY
    return TouchstoneTags(**{f.name: getattr(tags, f.name) for f in fields(Tags)},
                          touchstone=replace(declared, **offered))


def capabilities(model) -> Capabilities:
    """What `model` declares it offers; LIBRARY for an estimator that declares nothing."""
    tags = get_tags(model)
    return tags.touchstone if isinstance(tags, TouchstoneTags) else LIBRARY


def model_name(model) -> str:
    """The model's name in metrics and reports, as it declares it."""
    named_by = capabilities(model).named_by
    if named_by == "kind":
        return f"{type(model).__name__}({model.kind})"
    if named_by == "network":
        return type(model.module_).__name__
    return type(model).__name__


def model_size(model) -> dict:
    """{n_parameters: ...} or {n_nodes: ...} as the model declares its size; {} when it declares none."""
    size = capabilities(model).size
    return {} if size is None else {size: int(getattr(model, size + "_"))}


def fit(model, X, y, X_val=None, y_val=None, epoch_callback=None, groups=None):
    """Fit `model` with the shared signature when it takes it, else as a library estimator: fit(X, y)."""
    if capabilities(model).shared_fit:
        return model.fit(X, y, X_val, y_val, epoch_callback=epoch_callback, groups=groups)
    return model.fit(X, y)
