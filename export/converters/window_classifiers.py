"""Window classifiers (a time-series net, models/timeseries_classifier.py; a ROCKET model,
models/rocket/classifier.py) to ONNX through torch.onnx with the pipeline's preprocessing folded
in (export/torch_graphs.py WindowClassifier): raw window [batch, channels, steps] -> FSR
calibration -> decimation -> scaling -> the model's module -> probabilities."""
import torch

from export.converters.registry import Output, converts
from export.torch_graphs import WindowClassifier, to_onnx
from models.rocket.classifier import RocketClassifier
from models.timeseries_classifier import TimeSeriesClassifier


@converts(TimeSeriesClassifier, RocketClassifier)
def window_classifier_graph(piece, model) -> Output:
    example = torch.zeros(2, piece.n_inputs, piece.pipeline.raw_length)
    proto = to_onnx(WindowClassifier(piece.pipeline), example, "window", "probabilities", piece.opset)
    return Output(piece.builder.add_model(proto, {"window": piece.inputs}, piece.prefix)["probabilities"])
