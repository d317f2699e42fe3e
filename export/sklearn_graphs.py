"""Seed 001's classic regressors (models/classic_regressors.py) to ONNX: scaled float32
features in, targets in units out (`features` -> `y`).

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

A table's classifier (models/classic_classifiers.py) goes through skl2onnx whole (trees, MLP,
logistic regression: float32, as the trees compute), its probabilities then temperature-scaled
as TableClassifier.predict_proba does: softmax(beta * log(p + EPS)).
"""
import numpy as np
import onnx
from onnx import TensorProto
from skl2onnx import convert_sklearn
from skl2onnx.common.data_types import DoubleTensorType, FloatTensorType
from sklearn.gaussian_process import GaussianProcessRegressor

from export.graph_builder import GraphBuilder, tensor
from models.classic_classifiers import EPS, TableClassifier
from models.classic_regressors import ClassicRegressor


def _affine(builder, estimator, features64) -> str:
    """X w + b in float64 for a fitted LinearRegression or linear-kernel SVR: [batch, outputs]."""
    weights = np.atleast_2d(np.asarray(estimator.coef_, dtype=np.float64))     # [outputs, n_features]
    intercept = np.atleast_1d(np.asarray(estimator.intercept_, dtype=np.float64))
    product = builder.op("MatMul", [features64, builder.const(weights.T.copy(), "weights")])
    return builder.op("Add", [product, builder.const(intercept.reshape(1, -1), "intercept")])


def _gaussian_process(builder, estimator, features64, n_features, opset, prefix) -> str:
    proto = convert_sklearn(estimator, initial_types=[("features", DoubleTensorType([None, n_features]))],
                            target_opset={"": opset, "ai.onnx.ml": 3}, options={id(estimator): {"optim": "cdist"}})
    outputs = builder.add_model(proto, {"features": features64}, prefix)
    return next(iter(outputs.values()))  # skl2onnx's regressors have one output, `variable`


def classic_to_onnx(regressor, n_features: int, n_targets: int, opset: int) -> onnx.ModelProto:
    """One ONNX model `features` [batch, n_features] float32 -> `y` [batch, n_targets] float32 in
    units, for a fitted ClassicRegressor."""
    if not isinstance(regressor, ClassicRegressor):
        raise TypeError(f"no ONNX exporter for {type(regressor).__name__}")
    builder = GraphBuilder(opset)
    features64 = builder.op("Cast", ["features"], to=TensorProto.DOUBLE)
    columns = []
    for k, estimator in enumerate(regressor.estimators_):
        if isinstance(estimator, GaussianProcessRegressor):
            out = _gaussian_process(builder, estimator, features64, n_features, opset, f"piece{k}")
        else:
            out = _affine(builder, estimator, features64)
        # one multi-output piece gives every target; one SVR per target gives one column each
        width = n_targets if len(regressor.estimators_) == 1 else 1
        columns.append(builder.op("Reshape", [out, builder.const(np.array([-1, width], dtype=np.int64), "shape")]))
    standardised = columns[0] if len(columns) == 1 else builder.op("Concat", columns, axis=1)
    scale = builder.const(np.asarray(regressor.target_scale_, dtype=np.float64).reshape(1, -1), "target_scale")
    mean = builder.const(np.asarray(regressor.target_mean_, dtype=np.float64).reshape(1, -1), "target_mean")
    units = builder.op("Add", [builder.op("Mul", [standardised, scale]), mean])
    builder.identity(builder.op("Cast", [units], to=TensorProto.FLOAT), "y")
    return builder.build([tensor("features", ["batch", n_features])], [tensor("y", ["batch", n_targets])], {})


def table_classifier_to_onnx(classifier, n_features: int, opset: int) -> onnx.ModelProto:
    """One ONNX model `features` [batch, n_features] float32 -> `probabilities` [batch, n_classes]
    float32, calibrated, for a fitted TableClassifier."""
    if not isinstance(classifier, TableClassifier):
        raise TypeError(f"no ONNX exporter for {type(classifier).__name__}")
    estimator = classifier.estimator_
    proto = convert_sklearn(estimator, initial_types=[("features", FloatTensorType([None, n_features]))],
                            target_opset={"": opset, "ai.onnx.ml": 3}, options={id(estimator): {"zipmap": False}})
    builder = GraphBuilder(opset)
    raw = builder.add_model(proto, {"features": "features"}, "classifier")["probabilities"]
    logits = builder.op("Log", [builder.op("Add", [raw, builder.const(np.array(EPS, dtype=np.float32), "eps")])])
    scaled = builder.op("Mul", [logits, builder.const(np.array(classifier.temperature_beta_, dtype=np.float32), "beta")])
    builder.identity(builder.op("Softmax", [scaled], axis=1), "probabilities")
    n_classes = len(classifier.classes_)
    return builder.build([tensor("features", ["batch", n_features])], [tensor("probabilities", ["batch", n_classes])], {})
