"""What a run calls its model, one way for metrics.json, the log, TensorBoard and the figures.

A default run (model=auto) fits a choice of candidates and deploys one of them: the name a user
reads is the candidate's (`resmlp_seeds`), never the class that happens to implement it
(`KFoldBlend`, which is both a K-fold blend and, with resample=seeds, a seed ensemble), and the
members a blend or ensemble averages are said in words: how many, of what, trained how.
"""
from models.capabilities import capabilities, model_name

RESAMPLED = {"seeds": "seed-ensemble members, each trained on every training row with its own seed",
             "kfold": "K-fold members, each trained on all folds but one"}


def members(model) -> str | None:
    """The members a model averages or weighs, in words; None for a single model."""
    offers = capabilities(model)
    if offers.weighs_candidates:
        return "blend of " + ", ".join(model.names_)
    if offers.fold_costs and getattr(model, "models_", None):
        resample = model.get_params().get("resample", "kfold")
        return f"{len(model.models_)} {model_name(model.models_[0])} {RESAMPLED.get(resample, resample)}"
    return None


def run_model_name(model, choice=None) -> str:
    """The name a run reports: the chosen candidate's name under the default, else the model's own."""
    return choice.chosen_ if choice is not None else model_name(model)


def model_record(model, choice=None) -> dict:
    """metrics.json's naming keys: `model` (what the run reports and deploys), `model_class` (the
    class that implements it) and `members` (what it averages, in words) where there are any."""
    record = {"model": run_model_name(model, choice), "model_class": model_name(model)}
    described = members(model)
    if described:
        record["members"] = described
    return record


def fit_time_words(metrics: dict) -> str:
    """'resmlp_seeds (3 ResMLP seed-ensemble members, ...) fitted in 4.9 s (choosing among 2
    candidates took 8.8 s)' for a choice, else 'X fitted in 8.8 s': a choice's fit_time_s counts
    every candidate it fitted."""
    choice = metrics.get("choice")
    name = metrics["model"] + (f" ({metrics['members']})" if metrics.get("members") else "")
    if not choice:
        return f"{name} fitted in {metrics['fit_time_s']:.2f} s"
    own = choice["fit_time_s"].get(choice["chosen"])
    if own is None:   # the validation-weighted mixture: no fit of its own
        return f"{name} chosen in {metrics['fit_time_s']:.2f} s"
    fitted = len(choice["fit_time_s"])
    return (f"{name} fitted in {own:.2f} s (choosing among {fitted} candidate"
            f"{'s' if fitted != 1 else ''} took {metrics['fit_time_s']:.2f} s)")
