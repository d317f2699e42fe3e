"""Seed 001's classic regressors (models/classic_regressors.py) to ONNX: scaled float32 features
in, targets in units out.

Everything runs in float64 inside the graph. The two linear models are affine maps, y = X w + b:
linear regression's coefficients, and for the SVR with a linear kernel its primal weights
w = sum_i alpha_i sv_i (scikit-learn's `coef_`), which give the same prediction as the dual sum
over support vectors with no cancellation between them (skl2onnx's SVMRegressor sums the dual
form in float32: ~1e-4 relative error on ordinary presses, far more on far-extrapolated ones).
The Gaussian process goes through skl2onnx in float64: its prediction is a sum over ~10^3
training rows of kernel values times weights that cancel (shared/notes/facts.md: trees want
float32; a GP is the opposite case). The pieces' standardised outputs are concatenated and
turned back into units with the training targets' mean and spread, as
ClassicRegressor.predict does.
"""
import numpy as np
from onnx import TensorProto
from skl2onnx import convert_sklearn
from skl2onnx.common.data_types import DoubleTensorType

from export.converters.registry import Output, converts
from models.classic_regressors import ClassicRegressor


def _affine(builder, estimator, features64) -> str:
    """X w + b in float64 for a fitted LinearRegression or linear-kernel SVR: [batch, outputs]."""
    weights = np.atleast_2d(np.asarray(estimator.coef_, dtype=np.float64))     # [outputs, n_features]
    intercept = np.atleast_1d(np.asarray(estimator.intercept_, dtype=np.float64))
    product = builder.op("MatMul", [features64, builder.const(weights.T.copy(), "weights")])
    return builder.op("Add", [product, builder.const(intercept.reshape(1, -1), "intercept")])


def _gaussian_process(piece, estimator, features64, prefix) -> str:
    proto = convert_sklearn(estimator, initial_types=[("features", DoubleTensorType([None, piece.n_inputs]))],
                            target_opset={"": piece.opset, "ai.onnx.ml": 3},
                            options={id(estimator): {"optim": "cdist"}})
    outputs = piece.builder.add_model(proto, {"features": features64}, prefix)
    return next(iter(outputs.values()))  # skl2onnx's regressors have one output, `variable`


@converts(ClassicRegressor)
def classic_graph(piece, regressor) -> Output:
    builder, n_targets = piece.builder, piece.n_outputs
    features64 = builder.op("Cast", [piece.inputs], to=TensorProto.DOUBLE)
    columns = []
    for k, estimator in enumerate(regressor.estimators_):
        if regressor.kind == "gaussian_process":
            out = _gaussian_process(piece, estimator, features64, f"{piece.prefix}/piece{k}")
        else:
            out = _affine(builder, estimator, features64)
        # one multi-output piece gives every target; one SVR per target gives one column each
        width = n_targets if len(regressor.estimators_) == 1 else 1
        columns.append(builder.op("Reshape", [out, builder.const(np.array([-1, width], dtype=np.int64), "shape")]))
    standardised = columns[0] if len(columns) == 1 else builder.op("Concat", columns, axis=1)
    scale = builder.const(np.asarray(regressor.target_scale_, dtype=np.float64).reshape(1, -1), "target_scale")
    mean = builder.const(np.asarray(regressor.target_mean_, dtype=np.float64).reshape(1, -1), "target_mean")
    units = builder.op("Add", [builder.op("Mul", [standardised, scale]), mean])
    return Output(builder.op("Cast", [units], to=TensorProto.FLOAT))
