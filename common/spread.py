"""Mean ± sd of repeated measurements (seeds, splits, repeats), the one way every report and
benchmark writes a spread: the sample standard deviation (ddof 1), 0 for a single value."""
import numpy as np


def mean_and_sd(values) -> tuple[float, float]:
    values = np.asarray(values, dtype=float)
    return float(values.mean()), float(values.std(ddof=1)) if values.size > 1 else 0.0


def format_mean_sd(values, spec=".2f", separator: str = " ± ", one_value: str | None = None,
                   missing: str | None = None) -> str:
    """'mean ± sd' with both numbers in the format `spec` (e.g. '.3f', ',.0f'; or a function of
    the mean giving one, for a format that follows the magnitude).

    `one_value`: a template a single value is written in instead of 'value ± 0' ('{}' stands for
    the value: '{} (1 seed)'). `missing`: None values are left out (a run that failed) and this is
    written when none is left."""
    if missing is not None:
        values = [v for v in values if v is not None]
        if not values:
            return missing
    mean, sd = mean_and_sd(values)
    spec = spec(mean) if callable(spec) else spec
    if one_value is not None and np.size(values) == 1:
        return one_value.format(format(mean, spec))
    return format_mean_and_sd(mean, sd, spec, separator)


def format_mean_and_sd(mean, sd, spec: str = ".2f", separator: str = " ± ", missing: str | None = None) -> str:
    """'mean ± sd' of a mean and an sd already computed (a pooled sd, a summary table's columns).
    With `missing` set, a mean that is not a finite number is written as `missing`, and an sd that
    is not one is left off (the mean alone)."""
    if missing is not None and not np.isfinite(mean):
        return missing
    if missing is not None and not np.isfinite(sd):
        return format(mean, spec)
    return f"{mean:{spec}}{separator}{sd:{spec}}"
