import inspect
import os
from pathlib import Path

import pytest
from hydra import compose, initialize_config_dir
from hypothesis import HealthCheck, settings

from common.threads import apply_threads, resolve_threads

# One thread per library, as train.py's default: tests run beside each other and other work.
apply_threads(resolve_threads(os.environ.get("TOUCHSTONE_THREADS", "1")))

# Hypothesis profiles. "ci" (the default) is derandomised with no example database, so a failure
# reproduces exactly and prints its falsifying example; its per-test example counts add up to
# more than 10,000 generated examples (tests/models/test_numerical_properties.py). "thorough" runs 20x more,
# random: pytest --hypothesis-profile=thorough tests/models/test_numerical_properties.py
settings.register_profile("ci", derandomize=True, database=None, deadline=None, print_blob=True,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.register_profile("thorough", max_examples=2000, deadline=None, print_blob=True,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

CONFIG_DIR = str(Path(__file__).resolve().parents[1] / "configs")

# Tiny settings that keep a whole run to a few seconds.
TINY = ["scene.n_samples=120", "scene.grid_nodes=21", "scene.progress=false",
        "trainer.max_epochs=4", "trainer.progress=false",
        "model.n_estimators=10"]


@pytest.fixture
def compose_config():
    """Compose the real Hydra config with overrides, as train.py would see it."""
    def _compose(overrides=()):
        with initialize_config_dir(config_dir=CONFIG_DIR, version_base="1.3"):
            return compose(config_name="config", overrides=list(overrides))
    return _compose


def tiny(model: str) -> list[str]:
    overrides = [f"model={model}"] + [o for o in TINY if not o.startswith("model.")]
    if model in ("random_forest", "extra_trees"):
        overrides.append("model.n_estimators=10")
    if model == "blend":  # 160 presses leave 24 calibration rows, enough for a 95 % quantile
        overrides = [o for o in overrides if not o.startswith("scene.n_samples")]
        overrides += ["scene.n_samples=160", "data.n_folds=2", "analysis.progress=false", "analysis.ablation=true",
                      "model.candidates.random_forest.estimator.n_estimators=10",
                      "model.candidates.extra_trees.estimator.n_estimators=10"]
    return overrides


@pytest.fixture
def counted_effects():
    """counted(effects) -> (the same effects, each counting its calls; the counts by name): for
    the scene contract's test that only listed effects ever run."""
    def counted(effects):
        calls = {name: 0 for name in effects}

        def wrap(name, fn):
            def wrapped(*args, **kwargs):
                calls[name] += 1
                return fn(*args, **kwargs)
            wrapped.__signature__ = inspect.signature(fn)  # scenes read an effect's parameters from it
            return wrapped
        return {name: wrap(name, fn) for name, fn in effects.items()}, calls
    return counted
