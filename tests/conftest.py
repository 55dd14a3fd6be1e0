"""Suite-wide setup: each pytest-xdist worker keeps to one core.

The suite runs in two worker processes (``-n 2`` in pyproject.toml) on a 2-core machine. Numerical code that
sizes its threads by the cores it may use (OpenBLAS, Dr.Jit's LLVM pool, vissim's own thread pools) would
otherwise start two threads per worker, four on two cores, and the workers would slow each other down.
"""

import os

_WORKER = os.environ.get("PYTEST_XDIST_WORKER", "")
if _WORKER.startswith("gw") and hasattr(os, "sched_setaffinity"):
    cores = sorted(os.sched_getaffinity(0))
    workers = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
    if len(cores) >= workers > 1:
        os.sched_setaffinity(0, {cores[int(_WORKER[2:]) % len(cores)]})
        for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ.setdefault(name, "1")
