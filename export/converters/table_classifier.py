"""A table's classifier (models/classic_classifiers.py) to ONNX: the scikit-learn classifier
through skl2onnx whole (trees, MLP, logistic regression: float32, as the trees compute), its
probabilities then temperature-scaled as TableClassifier.predict_proba does:
softmax(beta * log(p + EPS)). Standardised float32 features in, probabilities out."""
import numpy as np
from skl2onnx import convert_sklearn
from skl2onnx.common.data_types import FloatTensorType

from export.converters.registry import Output, converts
from models.classic_classifiers import EPS, TableClassifier


@converts(TableClassifier)
def table_classifier_graph(piece, classifier) -> Output:
    builder, estimator = piece.builder, classifier.estimator_
    proto = convert_sklearn(estimator, initial_types=[("features", FloatTensorType([None, piece.n_inputs]))],
                            target_opset={"": piece.opset, "ai.onnx.ml": 3}, options={id(estimator): {"zipmap": False}})
    raw = builder.add_model(proto, {"features": piece.inputs}, f"{piece.prefix}/classifier")["probabilities"]
    logits = builder.op("Log", [builder.op("Add", [raw, builder.const(np.array(EPS, dtype=np.float32), "eps")])])
    scaled = builder.op("Mul", [logits, builder.const(np.array(classifier.temperature_beta_, dtype=np.float32), "beta")])
    return Output(builder.op("Softmax", [scaled], axis=1))
