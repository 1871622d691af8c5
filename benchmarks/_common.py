"""What every benchmark script shares: the machine line for the recorded tables and best-of timing."""
from __future__ import annotations

import importlib
import os
import platform
import time

import numpy as np
import scipy

_LABELS = {"flint": "python-flint"}


def machine_info(*optional: str) -> str:
    """CPU, cores, Python, numpy, scipy, the versions of the ``optional`` modules and the BLAS threads."""
    cpu = "unknown"
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    parts = [f"CPU {cpu}, {os.cpu_count()} cores (shared with other jobs)", f"Python {platform.python_version()}",
             f"numpy {np.__version__}", f"scipy {scipy.__version__}"]
    for name in optional:
        try:
            version = getattr(importlib.import_module(name), "__version__", "?")
        except ImportError:
            version = "not installed"
        parts.append(f"{_LABELS.get(name, name)} {version}")
    parts.append(f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}")
    return "; ".join(parts)


def best_of(fun, repeat: int = 3, number: int = 1, clock=time.perf_counter):
    """(least time per call over ``repeat`` runs of ``number`` calls, the last result)."""
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = clock()
        for _ in range(number):
            out = fun()
        best = min(best, (clock() - t0) / number)
    return best, out
