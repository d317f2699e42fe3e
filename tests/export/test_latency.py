"""The eager latency baseline is the estimator as deployed: forests predict on one job at batch 1."""
import numpy as np
from sklearn.ensemble import ExtraTreesRegressor, RandomForestRegressor
from sklearn.multioutput import MultiOutputRegressor

from export.latency import EAGER_BASELINE, measure, single_job
from models.deployable import RegressionPipeline
from models.weighted_blend import ValidationWeightedBlend


def test_every_forest_inside_a_model_predicts_on_one_job():
    X, y = np.random.default_rng(0).normal(size=(40, 3)), np.random.default_rng(1).normal(size=(40, 2))
    forests = {"rf": RandomForestRegressor(n_estimators=3, n_jobs=4).fit(X, y),
               "mo": MultiOutputRegressor(ExtraTreesRegressor(n_estimators=3, n_jobs=-1), n_jobs=2).fit(X, y)}
    blend = ValidationWeightedBlend.__new__(ValidationWeightedBlend)
    blend.fitted_ = forests  # an ours-wrapper holding estimators in a dict
    assert single_job(blend) >= 4
    assert forests["rf"].n_jobs == 1 and forests["mo"].n_jobs == 1
    assert all(e.n_jobs == 1 for e in forests["mo"].estimators_)


def test_the_measured_costs_say_what_the_eager_baseline_is():
    X = np.random.default_rng(0).normal(size=(30, 2))
    forest = RandomForestRegressor(n_estimators=3, n_jobs=2).fit(X, X[:, 0])
    pipeline = RegressionPipeline(channel_names=["a", "b"], target_names=["t"], feature_groups=[], feature_names=[],
                                  scaler_mean=np.zeros(2), scaler_scale=np.ones(2), model=forest, examples=X)
    pipeline.features = lambda readings: readings
    cost = measure(pipeline, None, budget_s=0.01)
    assert cost["eager_baseline"] == EAGER_BASELINE and "n_jobs=1" in EAGER_BASELINE
    assert forest.n_jobs == 1 and cost["eager_estimators_set_to_one_job"] == 1
