"""Models of Touchstone. Every model follows one estimator contract (scikit-learn's):

- `__init__` only stores its keyword arguments (so `sklearn.base.clone` works);
- `fit(X, y, X_val=None, y_val=None, epoch_callback=None, groups=None)` returns self; learned
  state ends in `_`;
- `predict(X)` returns targets in the units `fit` saw.
Trees ignore the validation data, the callback and the groups; nets use the validation data
for early stopping and the callback for per-epoch logging; blends use the groups to keep every
repeat of a press in one fold.

Layout: nets/ holds the torch networks (one file each); this folder the estimators and
ensembles; report/ turns a fitted model into metrics, figures, TensorBoard and files; runs/
holds the regression and classification runs that train.py starts.
"""
