"""Tree models to ONNX with skl2onnx: scaled float32 features in, targets in units out.

skl2onnx declares multi-target forests' output as [None, 1] unless told the real shape, and
onnxruntime then warns on every call (shared/notes/facts.md): the output type is given.
TreeEnsembleRegressor runs in float32: a feature exactly on a split threshold can take the
other branch than scikit-learn's float64 comparison (counted in the parity tests).
"""
import onnx
from skl2onnx import convert_sklearn
from skl2onnx.common.data_types import FloatTensorType


def tree_to_onnx(regressor, n_features: int, n_targets: int, opset: int) -> onnx.ModelProto:
    return convert_sklearn(regressor.estimator_, initial_types=[("features", FloatTensorType([None, n_features]))],
                           final_types=[("y", FloatTensorType([None, n_targets]))],
                           target_opset={"": opset, "ai.onnx.ml": 3})
