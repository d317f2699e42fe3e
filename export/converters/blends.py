"""Ensembles to ONNX, their members through the registry: a K-fold blend (models/kfold_blend.py)
as its folds' mean and unbiased variance (sigma_model^2, eq. 21), a validation-weighted blend
(models/weighted_blend.py) as its weighted candidates and, for calibrated intervals, their
mixture variance sum_m w_m (sigma_model,m^2 + (yhat_m - yhat)^2); either, asked for intervals and
calibrated, with the interval's half-width (eq. 23-24)."""
from dataclasses import replace

import numpy as np
from onnx import TensorProto

from export.converters.registry import Output, convert, converter_for, converts
from models.kfold_blend import KFoldBlend
from models.weighted_blend import ValidationWeightedBlend


@converts(KFoldBlend)
def kfold_graph(piece, model) -> Output:
    intervals = piece.intervals and model.calibrated
    member_graph = converter_for(model.models_[0])   # the folds are copies of one estimator
    folds = [member_graph(replace(piece, prefix=f"{piece.prefix}/fold{k}", intervals=False), member).value
             for k, member in enumerate(model.models_)]
    mean, variance = piece.builder.mean_and_variance(folds)
    half = piece.builder.half_width(variance, model.data_variance_, model.conformal_scale_) if intervals else None
    return Output(mean, variance, half)


@converts(ValidationWeightedBlend)
def weighted_blend_graph(piece, model) -> Output:
    intervals, builder = piece.intervals and model.calibrated, piece.builder
    parts = [convert(replace(piece, prefix=f"cand{i}", intervals=False), member)
             for i, member in enumerate(model.models_.values())]
    weights = [builder.const(w.astype(np.float32), "weight") for w in model.weights_]
    terms = [builder.op("Mul", [part.value, w]) for part, w in zip(parts, weights)]
    mean = terms[0]
    for term in terms[1:]:
        mean = builder.op("Add", [mean, term])
    if not intervals:
        return Output(mean)
    # The mixture variance in float64: squares of far-extrapolated predictions (an open channel
    # at 1e9 ohm) overflow float32 long before their square roots would.
    mean64, variance = builder.op("Cast", [mean], to=TensorProto.DOUBLE), None
    for part, w in zip(parts, model.weights_):
        gap = builder.op("Sub", [builder.op("Cast", [part.value], to=TensorProto.DOUBLE), mean64])
        spread = builder.op("Mul", [gap, gap])
        if part.variance is not None:
            spread = builder.op("Add", [spread, part.variance])
        term = builder.op("Mul", [spread, builder.const(w.astype(np.float64), "weight64")])
        variance = term if variance is None else builder.op("Add", [variance, term])
    return Output(mean, variance, builder.half_width(variance, model.data_variance_, model.conformal_scale_))
