"""The ONNX converter registry: a converter per model class, found by the model's type (its
class, then its bases in method-resolution order), as skl2onnx finds its converters.

A converter adds one model's nodes to the graph a pipeline is built in (export/pipelines.py):
`convert(piece, model) -> Output`, reading the tensor `piece.inputs` (standardised features, or
a raw window for a window classifier) and giving targets in units (regression: with the model
variance in float64 where the model has one, and with `piece.intervals` the calibrated interval's
half-width) or class probabilities. A
library estimator no converter of ours is registered for goes through skl2onnx's own registry
(export/converters/library.py); a class neither knows is a LookupError naming it and both.
"""
from dataclasses import dataclass

REGISTRY = "Touchstone's ONNX converter registry (export/converters/)"
_CONVERTERS = {}
_FALLBACK = {}   # "converter": the one for classes no converter of ours is registered for (library.py)


@dataclass(frozen=True)
class Piece:
    """Where a model's nodes go and what they read (a member's piece: dataclasses.replace, another prefix)."""
    builder: object        # export/graph_builder.py GraphBuilder of the whole pipeline
    inputs: str            # the tensor the model reads
    n_inputs: int          # features (or channels of a window)
    n_outputs: int         # targets or classes
    opset: int
    prefix: str            # the model's nodes are named under it
    intervals: bool = False  # regression: the model's calibrated interval half-width is wanted too
    pipeline: object = None  # the deployable pipeline (a window classifier folds its preprocessing in)


@dataclass(frozen=True)
class Output:
    value: str                     # targets in units, or class probabilities
    variance: str | None = None    # regression: the model variance (float64) where the model has one
    half_width: str | None = None  # regression: the calibrated interval's half-width, when asked for


def converts(*classes):
    """Register the decorated function as the ONNX converter of `classes` (and their subclasses)."""
    def register(convert):
        for cls in classes:
            _CONVERTERS[cls] = convert
        return convert
    return register


def converts_the_rest(convert):
    """Register the decorated function for every class no converter of ours is registered for."""
    _FALLBACK["converter"] = convert
    return convert


def convert(piece: Piece, model) -> Output:
    """The nodes of `model`, added by its class's converter."""
    return converter_for(model)(piece, model)


def converter_for(model):
    """The converter registered for the model's class, or for the nearest of its bases."""
    for cls in type(model).__mro__:
        if cls in _CONVERTERS:
            return _CONVERTERS[cls]
    if _FALLBACK:
        return _FALLBACK["converter"]
    raise LookupError(f"no ONNX converter for {type(model).__module__}.{type(model).__qualname__} in {REGISTRY}")
