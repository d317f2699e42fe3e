"""Turn a deployable pipeline (models/deployable.py) into one self-contained ONNX model.

Regression: `channels` [batch, n_channels] float64 raw readings -> (the data set's min-max
normalisation, for models trained on normalised channels) -> physics features and scaler
-> the model(s) -> `prediction` [batch, n_targets] in units, and for models with calibrated
intervals `interval_half_width` (the conformal scale times sigma_total, eq. 21-24, computed in
the graph from the fold models' spread, the candidates' disagreement and sigma_data).
Classification table: `channels` as for regression -> the same front end -> the classifier's
probabilities -> `probabilities` [batch, n_classes]. Time series: `window` [batch, channels,
steps] float32 raw window -> `probabilities`. The model's own nodes come from its class's
converter (export/converters/). Metadata describe the inputs and outputs so the predict side can
check a file against them: `kind` (regression or classification), `input` (channels or
window), `channels`, `outputs`, and `targets` / `classes` (with `label`, the target column, for
a table classifier).
"""
import functools
import json
import logging
import time
import tomllib
from pathlib import Path

import onnx
import torch
from onnx import TensorProto

from common.atomic import atomic_write
from export.converters.registry import Piece, convert
from export.graph_builder import GraphBuilder, tensor
from export.torch_graphs import RegressionFrontEnd, to_onnx
from models.capabilities import capabilities
from models.deployable import RegressionPipeline, TableClassifierPipeline, TimeSeriesPipeline

log = logging.getLogger(__name__)
ROOT = Path(__file__).resolve().parents[1]
REGISTRY = "the pipeline graphs (export/pipelines.py GRAPHS)"


def touchstone_version() -> str:
    """The package version, kept in one place: pyproject.toml."""
    with open(ROOT / "pyproject.toml", "rb") as handle:
        return tomllib.load(handle)["project"]["version"]


def _table_front(pipeline, opset) -> tuple[GraphBuilder, str]:
    """A builder whose graph starts: raw `channels` -> (normalisation) -> physics features,
    standardised; and the name of that `features` tensor."""
    front = to_onnx(RegressionFrontEnd(pipeline.feature_groups, pipeline.scaler_mean, pipeline.scaler_scale,
                                       pipeline.normalisation),
                    torch.ones(2, len(pipeline.channel_names), dtype=torch.float64), "channels", "features", opset)
    builder = GraphBuilder(opset)
    return builder, builder.add_model(front, {"channels": "channels"}, "front")["features"]


class RegressionGraph:
    @staticmethod
    def metadata(pipeline) -> dict[str, str]:
        units = {t: t.rsplit("_", 1)[-1] for t in pipeline.target_names}
        return {"kind": "regression", "input": "channels", "targets": json.dumps(pipeline.target_names),
                "target_units": json.dumps(units), "features": json.dumps(pipeline.feature_names)}

    @staticmethod
    def outputs(pipeline) -> list[str]:
        intervals = capabilities(pipeline.model).intervals and pipeline.model.calibrated
        return ["prediction"] + (["interval_half_width"] if intervals else [])

    @staticmethod
    def graph(pipeline, opset: int) -> tuple[GraphBuilder, list, list]:
        """With the calibrated interval's half-width where the model gives one."""
        builder, features = _table_front(pipeline, opset)
        n_targets = len(pipeline.target_names)
        piece = Piece(builder, features, len(pipeline.feature_names), n_targets, opset, "model", intervals=True)
        out = convert(piece, pipeline.model)
        outputs = [tensor(builder.identity(out.value, "prediction"), ["batch", n_targets])]
        if out.half_width is not None:
            outputs.append(tensor(builder.identity(out.half_width, "interval_half_width"), ["batch", n_targets]))
        return builder, [tensor("channels", ["batch", len(pipeline.channel_names)], TensorProto.DOUBLE)], outputs


class TableClassifierGraph:
    @staticmethod
    def metadata(pipeline) -> dict[str, str]:
        return {"kind": "classification", "input": "channels", "label": pipeline.label,
                "classes": json.dumps(pipeline.classes), "features": json.dumps(pipeline.feature_names)}

    @staticmethod
    def outputs(pipeline) -> list[str]:
        return ["probabilities"]

    @staticmethod
    def graph(pipeline, opset: int) -> tuple[GraphBuilder, list, list]:
        builder, features = _table_front(pipeline, opset)
        piece = Piece(builder, features, len(pipeline.feature_names), len(pipeline.classes), opset, "model")
        builder.identity(convert(piece, pipeline.model).value, "probabilities")
        return (builder, [tensor("channels", ["batch", len(pipeline.channel_names)], TensorProto.DOUBLE)],
                [tensor("probabilities", ["batch", len(pipeline.classes)])])


class TimeSeriesGraph:
    @staticmethod
    def metadata(pipeline) -> dict[str, str]:
        return {"kind": "classification", "input": "window", "classes": json.dumps(pipeline.classes),
                "window_steps": str(pipeline.raw_length), "decimate": str(pipeline.decimate),
                # the rate of the raw windows the graph takes, as the data declared it; unknown when they did not
                "sample_rate_hz": str(pipeline.description.get("sample_rate_hz") or "unknown")}

    outputs = TableClassifierGraph.outputs

    @staticmethod
    def graph(pipeline, opset: int) -> tuple[GraphBuilder, list, list]:
        n_channels = len(pipeline.channel_names)
        builder = GraphBuilder(opset)
        piece = Piece(builder, "window", n_channels, len(pipeline.classes), opset, "net", pipeline=pipeline)
        builder.identity(convert(piece, pipeline.model).value, "probabilities")
        return (builder, [tensor("window", ["batch", n_channels, pipeline.raw_length])],
                [tensor("probabilities", ["batch", len(pipeline.classes)])])


# The graph of each kind of deployable pipeline, found by the pipeline's type
GRAPHS = {RegressionPipeline: RegressionGraph, TableClassifierPipeline: TableClassifierGraph,
          TimeSeriesPipeline: TimeSeriesGraph}


def graph_of(pipeline):
    for cls in type(pipeline).__mro__:
        if cls in GRAPHS:
            return GRAPHS[cls]
    raise LookupError(f"no ONNX graph for a {type(pipeline).__module__}.{type(pipeline).__qualname__} in {REGISTRY}")


def metadata_for(pipeline, config_hash: str, opset: int, outputs: list[str] | None = None) -> dict[str, str]:
    """The model file's metadata; `outputs`: the graph's outputs, by default those its model declares."""
    kind = graph_of(pipeline)
    common = {"touchstone_version": touchstone_version(), "config_hash": config_hash, "opset": str(opset),
              "channels": json.dumps(pipeline.channel_names), "model": type(pipeline.model).__name__}
    return {**common, **kind.metadata(pipeline),
            "outputs": json.dumps(kind.outputs(pipeline) if outputs is None else outputs)}


def export_pipeline(pipeline, opset: int, config_hash: str) -> onnx.ModelProto:
    """`config_hash`: export/run_export.py's config_hash of the run's configuration, recorded in the
    metadata; the metadata's `outputs` are the ones the graph gives."""
    metadata = metadata_for(pipeline, config_hash, opset, outputs=[])
    builder, inputs, outputs = graph_of(pipeline).graph(pipeline, opset)
    metadata["outputs"] = json.dumps([output.name for output in outputs])
    return builder.build(inputs, outputs, metadata)


def write_onnx(pipeline, path, opset: int = 18, configuration_hash: str = "unknown", start: float | None = None) -> Path:
    """The one writer of a run's ONNX file: the pipeline as one self-contained graph, atomically."""
    start = time.perf_counter() if start is None else start
    data = export_pipeline(pipeline, opset, configuration_hash).SerializeToString()
    path = atomic_write(path, functools.partial(Path.write_bytes, data=data))
    log.info("exported %s (%.1f MB) in %.1f s", path, path.stat().st_size / 1e6, time.perf_counter() - start)
    return path
