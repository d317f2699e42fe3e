"""Models of Touchstone. Every model follows one estimator contract (scikit-learn's):

- `__init__` only stores its keyword arguments (so `sklearn.base.clone` works);
- `fit(X, y, X_val=None, y_val=None, epoch_callback=None)` returns self; learned state ends in `_`;
- `predict(X)` returns targets in the units `fit` saw.
Trees ignore the validation data and the callback; nets use them for early stopping and
for per-epoch logging.
"""
