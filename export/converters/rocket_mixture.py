"""The ROCKET-family mixture (models/rocket/mixture.py) to ONNX as one graph: its module computes
the transform once, every member's head as one matrix product, a softmax per member and the
validation-weighted sum (as the log of the mixture, which the window classifier's softmax turns
back into the probabilities), so the window classifiers' torch trace (export/converters/
window_classifiers.py: preprocessing folded in, raw window -> probabilities) exports it whole."""
from export.converters.registry import converts
from export.converters.window_classifiers import window_classifier_graph
from models.rocket.mixture import MixedRocketClassifier

converts(MixedRocketClassifier)(window_classifier_graph)
