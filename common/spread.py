"""Mean ± sd of repeated measurements (seeds, splits, repeats), the one way every report and
benchmark writes a spread: the sample standard deviation (ddof 1), 0 for a single value."""
import numpy as np


def mean_and_sd(values) -> tuple[float, float]:
    values = np.asarray(values, dtype=float)
    return float(values.mean()), float(values.std(ddof=1)) if values.size > 1 else 0.0


def format_mean_sd(values, spec: str = ".2f", separator: str = " ± ") -> str:
    """'mean ± sd' with both numbers in the format `spec` (e.g. '.3f', ',.0f')."""
    mean, sd = mean_and_sd(values)
    return f"{mean:{spec}}{separator}{sd:{spec}}"
