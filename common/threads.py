"""How many threads Touchstone's numeric libraries may use: one setting, applied before heavy work.

Left to themselves torch, the BLAS behind numpy and scipy, OpenMP and onnxruntime each start one
thread per core. On a quiet machine that is fine; beside any other busy process (a second run,
a sweep's parallel jobs, a test suite) their threads wait on each other. Measured on a 2-core
machine (bench/threads.py, README "Speed, threads and progress"): with every library's default
the default run, a resmlp run and a PR-CNN epoch ran 2.3-2.8x slower beside one busy process;
with one thread 0.97-1.10x. On an idle machine one thread costs 10 % on the default run and 60 %
on a PR-CNN epoch, so the default is one thread per process (robust wherever it runs) and
`threads=all` gives every core to a run that has the machine to itself.

The setting comes from the config (`threads=2`) or, for scripts and child processes, from the
environment variable TOUCHSTONE_THREADS. Applying it sets the usual environment variables (for
pools created later and for child processes), torch's intra-op threads, and the pools that are
already loaded (threadpoolctl).
"""
import os
import sys

from common.errors import InputError

ENVIRONMENT_VARIABLE = "TOUCHSTONE_THREADS"
POOL_VARIABLES = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                  "NUMEXPR_NUM_THREADS", "VECLIB_MAXIMUM_THREADS")


def resolve_threads(setting, parallel_jobs: int = 1) -> int:
    """Threads for one process: a positive integer, or `all` = the cores shared among
    `parallel_jobs` processes running side by side (a joblib sweep)."""
    if isinstance(setting, str) and setting.strip().lower() == "all":
        return max(1, (os.cpu_count() or 1) // max(1, int(parallel_jobs)))
    try:
        threads = int(setting)
        exact = float(setting) == threads
    except (TypeError, ValueError):
        exact = False
    if not exact or threads < 1 or isinstance(setting, bool):
        raise InputError(f"threads must be a positive integer or 'all', got {setting!r}")
    return threads


def apply_threads(threads: int) -> None:
    """Limit every numeric library of this process (and the processes it starts) to `threads`."""
    for name in (ENVIRONMENT_VARIABLE, *POOL_VARIABLES):
        os.environ[name] = str(threads)
    if "torch" in sys.modules:
        import torch
        torch.set_num_threads(threads)
    from threadpoolctl import threadpool_limits  # BLAS/OpenMP pools loaded before this call
    threadpool_limits(threads)


def configured_threads() -> int | None:
    """The setting in force (from TOUCHSTONE_THREADS), or None when none was given."""
    value = os.environ.get(ENVIRONMENT_VARIABLE)
    return resolve_threads(value) if value else None
