"""The one switch from a tree `kind` to scikit-learn's estimator, for regression (models/trees.py)
and classification tables (models/classic_classifiers.py): the same settings grow the same
kind of tree whichever the target is.
"""
from sklearn.ensemble import ExtraTreesClassifier, ExtraTreesRegressor, RandomForestClassifier, RandomForestRegressor
from sklearn.tree import DecisionTreeClassifier, DecisionTreeRegressor, ExtraTreeClassifier, ExtraTreeRegressor
from sklearn.tree._tree import Tree

from common.threads import configured_threads
from models.storable import storable

TREE_KINDS = ("decision_tree", "random_forest", "extra_trees")
# kind -> (regressor, classifier); a single tree takes no n_estimators and no n_jobs
FORESTS = {"decision_tree": (DecisionTreeRegressor, DecisionTreeClassifier),
           "random_forest": (RandomForestRegressor, RandomForestClassifier),
           "extra_trees": (ExtraTreesRegressor, ExtraTreesClassifier)}
SINGLE_TREES = {"decision_tree"}

# What a fitted forest holds: the ensembles, their trees and the trees' Cython state.
storable(*(cls for pair in FORESTS.values() for cls in pair), ExtraTreeRegressor, ExtraTreeClassifier)
storable(Tree, called=True)


def forest(kind: str, classifier: bool, n_estimators, max_depth, max_features, min_samples_leaf, n_jobs, seed):
    """The unfitted scikit-learn tree or forest of `kind` (one of TREE_KINDS; None for another).
    n_jobs None: the run's thread setting (common/threads.py), so forests do not fight whatever
    else runs on the machine; -1 still means every core."""
    if kind not in FORESTS:
        return None
    settings = dict(max_depth=max_depth, max_features=max_features, min_samples_leaf=min_samples_leaf,
                    random_state=seed)
    if kind not in SINGLE_TREES:
        settings.update(n_estimators=n_estimators, n_jobs=n_jobs if n_jobs is not None else (configured_threads() or 1))
    return FORESTS[kind][int(classifier)](**settings)
