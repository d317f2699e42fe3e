"""ONNX export of Touchstone's deployable pipelines, and their onnxruntime side.

export/ reads what models/ produced (a run's pipeline.npz) and never the other way round.
"""
