"""A library estimator (a scikit-learn regressor or classifier named by `_target_` in a model
config) to ONNX through skl2onnx's own converter registry: standardised float32 features in,
targets [batch, n_targets] or class probabilities out."""
import numpy as np
from skl2onnx import convert_sklearn
from skl2onnx.common.data_types import FloatTensorType
from skl2onnx.common.exceptions import MissingConverter, MissingShapeCalculator
from sklearn.base import is_classifier

from export.converters.registry import REGISTRY, Output, converts_the_rest


@converts_the_rest
def skl2onnx_graph(piece, model) -> Output:
    classifier = is_classifier(model)
    try:
        proto = convert_sklearn(model, initial_types=[("features", FloatTensorType([None, piece.n_inputs]))],
                                target_opset={"": piece.opset, "ai.onnx.ml": 3},
                                options={id(model): {"zipmap": False}} if classifier else None)
    except (MissingConverter, MissingShapeCalculator):
        raise LookupError(f"no ONNX converter for {type(model).__module__}.{type(model).__qualname__} in {REGISTRY} "
                          "nor in skl2onnx's registry") from None
    outputs = piece.builder.add_model(proto, {"features": piece.inputs}, piece.prefix)
    if classifier:
        return Output(outputs["probabilities"])
    # one output, `variable`: [batch, 1] for one target, whatever skl2onnx declares
    shape = piece.builder.const(np.array([-1, piece.n_outputs], dtype=np.int64), "shape")
    return Output(piece.builder.op("Reshape", [next(iter(outputs.values())), shape]))
