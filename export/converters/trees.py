"""Tree models (models/trees.py) to ONNX with skl2onnx: scaled float32 features in, targets in
units out (the trees were mapped back to units when fitted).

skl2onnx declares multi-target forests' output as [None, 1] unless told the real shape, and
onnxruntime then warns on every call (shared/notes/facts.md): the output type is given.
TreeEnsembleRegressor runs in float32: a feature exactly on a split threshold can take the
other branch than scikit-learn's float64 comparison (counted in the parity tests).
"""
from skl2onnx import convert_sklearn
from skl2onnx.common.data_types import FloatTensorType

from export.converters.registry import Output, converts
from models.trees import TreeRegressor


@converts(TreeRegressor)
def tree_graph(piece, model) -> Output:
    proto = convert_sklearn(model.estimator_, initial_types=[("features", FloatTensorType([None, piece.n_inputs]))],
                            final_types=[("y", FloatTensorType([None, piece.n_outputs]))],
                            target_opset={"": piece.opset, "ai.onnx.ml": 3})
    return Output(piece.builder.add_model(proto, {"features": piece.inputs}, piece.prefix)["y"])
