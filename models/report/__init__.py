"""What turns a fitted model into a report: metrics, figures, analysis, TensorBoard, files, and the Pareto report of a sweep."""
