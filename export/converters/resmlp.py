"""The residual MLP regressor (models/resmlp_regressor.py) to ONNX through torch.onnx, with its
own input standardisation and target de-standardisation (export/torch_graphs.py ResMLPInUnits):
standardised features -> targets in units."""
import torch

from export.converters.registry import Output, converts
from export.torch_graphs import ResMLPInUnits, to_onnx
from models.resmlp_regressor import ResMLPRegressor


@converts(ResMLPRegressor)
def resmlp_graph(piece, model) -> Output:
    proto = to_onnx(ResMLPInUnits(model), torch.zeros(2, piece.n_inputs), "features", "y", piece.opset)
    return Output(piece.builder.add_model(proto, {"features": piece.inputs}, piece.prefix)["y"])
