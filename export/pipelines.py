"""Turn a deployable pipeline (models/deployable.py) into one self-contained ONNX model.

Regression: `channels` [batch, n_channels] float64 raw readings -> (the data set's min-max
normalisation, for models trained on normalised channels) -> physics features and scaler
-> the model(s) -> `prediction` [batch, n_targets] in units, and for models with calibrated
intervals `interval_half_width` (the conformal scale times sigma_total, eq. 21-24, computed in
the graph from the fold models' spread, the candidates' disagreement and sigma_data).
Classification table: `channels` as for regression -> the same front end -> the classifier's
probabilities, temperature-calibrated (models/classic_classifiers.py) -> `probabilities`
[batch, n_classes]. Time series: `window` [batch, channels, steps] float32 raw window ->
`probabilities`. Metadata describe the inputs and outputs so the predict side can check a file
against them: `kind` (regression or classification), `input` (channels or window), `channels`,
`outputs`, and `targets` / `classes` (with `label`, the target column, for a table classifier).
"""
import json
import tomllib
from pathlib import Path

import numpy as np
import onnx
import torch
from onnx import TensorProto

from export.graph_builder import GraphBuilder, tensor
from export.torch_graphs import RegressionFrontEnd, ResMLPInUnits, WindowClassifier, to_onnx
from export.sklearn_graphs import classic_to_onnx, table_classifier_to_onnx
from export.tree_graphs import tree_to_onnx
from models.classic_regressors import ClassicRegressor
from models.kfold_blend import KFoldBlend
from models.deployable import RegressionPipeline, TableClassifierPipeline, TimeSeriesPipeline
from models.resmlp_regressor import ResMLPRegressor
from models.weighted_blend import ValidationWeightedBlend
from models.trees import TreeRegressor

ROOT = Path(__file__).resolve().parents[1]


def touchstone_version() -> str:
    """The package version, kept in one place: pyproject.toml."""
    with open(ROOT / "pyproject.toml", "rb") as handle:
        return tomllib.load(handle)["project"]["version"]


def _leaf(builder, model, features, n_features, n_targets, opset, prefix) -> str:
    if isinstance(model, ResMLPRegressor):
        proto = to_onnx(ResMLPInUnits(model), torch.zeros(2, n_features), "features", "y", opset)
    elif isinstance(model, TreeRegressor):
        proto = tree_to_onnx(model, n_features, n_targets, opset)
    elif isinstance(model, ClassicRegressor):  # seed 001's linear, SVR and GP regressors
        proto = classic_to_onnx(model, n_features, n_targets, opset)
    else:
        raise TypeError(f"no ONNX exporter for {type(model).__name__}")
    return builder.add_model(proto, {"features": features}, prefix)["y"]


def _mean_and_model_variance(builder, model, features, n_features, n_targets, opset, prefix):
    """(mean, model variance or None) of one candidate, K-fold blended or single."""
    if isinstance(model, KFoldBlend):
        folds = [_leaf(builder, m, features, n_features, n_targets, opset, f"{prefix}/fold{k}")
                 for k, m in enumerate(model.models_)]
        return builder.mean_and_variance(folds)
    return _leaf(builder, model, features, n_features, n_targets, opset, prefix), None


def _table_front(builder, pipeline, opset) -> str:
    """Raw `channels` -> (normalisation) -> physics features, standardised: the `features` tensor."""
    front = to_onnx(RegressionFrontEnd(pipeline.feature_groups, pipeline.scaler_mean, pipeline.scaler_scale,
                                       pipeline.normalisation),
                    torch.ones(2, len(pipeline.channel_names), dtype=torch.float64), "channels", "features", opset)
    return builder.add_model(front, {"channels": "channels"}, "front")["features"]


def table_classifier_graph(pipeline: TableClassifierPipeline, opset: int, metadata: dict) -> onnx.ModelProto:
    builder = GraphBuilder(opset)
    features = _table_front(builder, pipeline, opset)
    proto = table_classifier_to_onnx(pipeline.model, len(pipeline.feature_names), opset)
    builder.identity(builder.add_model(proto, {"features": features}, "model")["probabilities"], "probabilities")
    return builder.build([tensor("channels", ["batch", len(pipeline.channel_names)], TensorProto.DOUBLE)],
                         [tensor("probabilities", ["batch", len(pipeline.classes)])], metadata)


def regression_graph(pipeline: RegressionPipeline, opset: int, metadata: dict) -> onnx.ModelProto:
    n_channels, n_features, n_targets = len(pipeline.channel_names), len(pipeline.feature_names), len(pipeline.target_names)
    builder = GraphBuilder(opset)
    features = _table_front(builder, pipeline, opset)
    model = pipeline.model
    outputs = [tensor("prediction", ["batch", n_targets])]
    if isinstance(model, ValidationWeightedBlend):
        parts = [_mean_and_model_variance(builder, m, features, n_features, n_targets, opset, f"cand{i}")
                 for i, m in enumerate(model.models_.values())]
        weights = [builder.const(w.astype(np.float32), "weight") for w in model.weights_]
        terms = [builder.op("Mul", [m, w]) for (m, _), w in zip(parts, weights)]
        mean = terms[0]
        for term in terms[1:]:
            mean = builder.op("Add", [mean, term])
        builder.identity(mean, "prediction")
        if hasattr(model, "conformal_scale_"):
            # The mixture variance in float64: squares of far-extrapolated predictions (an open
            # channel at 1e9 ohm) overflow float32 long before their square roots would.
            double = lambda t: builder.op("Cast", [t], to=TensorProto.DOUBLE)  # noqa: E731
            mean64, variance = double(mean), None
            for (m, v), w in zip(parts, model.weights_):
                gap = builder.op("Sub", [double(m), mean64])
                spread = builder.op("Mul", [gap, gap])
                if v is not None:
                    spread = builder.op("Add", [spread, v])
                term = builder.op("Mul", [spread, builder.const(w.astype(np.float64), "weight64")])
                variance = term if variance is None else builder.op("Add", [variance, term])
            _interval(builder, variance, model)
            outputs.append(tensor("interval_half_width", ["batch", n_targets]))
    else:
        mean, variance = _mean_and_model_variance(builder, model, features, n_features, n_targets, opset, "model")
        builder.identity(mean, "prediction")
        if variance is not None and hasattr(model, "conformal_scale_"):
            _interval(builder, variance, model)
            outputs.append(tensor("interval_half_width", ["batch", n_targets]))
    return builder.build([tensor("channels", ["batch", n_channels], TensorProto.DOUBLE)], outputs, metadata)


def _interval(builder, model_variance, model):
    """half-width = q * sqrt(model variance + data variance), from a float64 model variance."""
    total = builder.op("Add", [model_variance, builder.const(model.data_variance_.astype(np.float64), "data_var")])
    sigma = builder.op("Sqrt", [total])
    half = builder.op("Mul", [sigma, builder.const(model.conformal_scale_.astype(np.float64), "conformal")])
    builder.identity(builder.op("Cast", [half], to=TensorProto.FLOAT), "interval_half_width")


def timeseries_graph(pipeline: TimeSeriesPipeline, opset: int, metadata: dict) -> onnx.ModelProto:
    n_channels = len(pipeline.channel_names)
    module = WindowClassifier(pipeline)
    proto = to_onnx(module, torch.zeros(2, n_channels, pipeline.raw_length), "window", "probabilities", opset)
    builder = GraphBuilder(opset)
    out = builder.add_model(proto, {"window": "window"}, "net")["probabilities"]
    builder.identity(out, "probabilities")
    return builder.build([tensor("window", ["batch", n_channels, pipeline.raw_length])],
                         [tensor("probabilities", ["batch", len(pipeline.classes)])], metadata)


def metadata_for(pipeline, config_hash: str, opset: int) -> dict[str, str]:
    common = {"touchstone_version": touchstone_version(), "config_hash": config_hash, "opset": str(opset),
              "channels": json.dumps(pipeline.channel_names), "model": type(pipeline.model).__name__}
    if isinstance(pipeline, RegressionPipeline):
        units = {t: t.rsplit("_", 1)[-1] for t in pipeline.target_names}
        return {**common, "kind": "regression", "input": "channels", "targets": json.dumps(pipeline.target_names),
                "target_units": json.dumps(units), "features": json.dumps(pipeline.feature_names),
                "outputs": json.dumps(["prediction"] + (["interval_half_width"] if hasattr(pipeline.model, "conformal_scale_") else []))}
    if isinstance(pipeline, TableClassifierPipeline):
        return {**common, "kind": "classification", "input": "channels", "label": pipeline.label,
                "classes": json.dumps(pipeline.classes), "features": json.dumps(pipeline.feature_names),
                "outputs": json.dumps(["probabilities"])}
    return {**common, "kind": "classification", "input": "window", "classes": json.dumps(pipeline.classes),
            "window_steps": str(pipeline.raw_length), "decimate": str(pipeline.decimate),
            # the rate of the raw windows the graph takes, as the data declared it; unknown when they did not
            "sample_rate_hz": str(pipeline.description.get("sample_rate_hz") or "unknown"),
            "outputs": json.dumps(["probabilities"])}


def export_pipeline(pipeline, opset: int, config_hash: str) -> onnx.ModelProto:
    """`config_hash`: export/run_export.py's config_hash of the run's configuration, recorded in the metadata."""
    metadata = metadata_for(pipeline, config_hash, opset)
    if isinstance(pipeline, RegressionPipeline):
        return regression_graph(pipeline, opset, metadata)
    if isinstance(pipeline, TableClassifierPipeline):
        return table_classifier_graph(pipeline, opset, metadata)
    return timeseries_graph(pipeline, opset, metadata)
