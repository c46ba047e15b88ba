"""Binding the worker processes of a local Dask cluster to one CPU core each (imported with dask.distributed)."""

from __future__ import annotations

import os
from typing import Any

from distributed import WorkerPlugin

__all__ = ["PinToCore"]


class PinToCore(WorkerPlugin):
    """Worker plugin: bind every thread of a local worker process to one CPU core, ``name % cores``.

    Why: XLA:CPU runs each process's kernels on a pool of threads that also spin while they wait.  Two unpinned
    worker processes on two cores took each design ~1.6x longer than one process alone (a 16-design sweep, 16x2
    grid, benchmarks/sweep_dask.py); pinned, each worker runs its designs at one core's speed.  Threads the
    process starts later inherit the binding.  Platforms without ``os.sched_setaffinity`` are left as they are.
    """

    name = "gfbjax-pin-to-core"

    def setup(self, worker: Any) -> None:
        if not hasattr(os, "sched_setaffinity"):
            return
        cores = sorted(os.sched_getaffinity(0))
        try:
            core = cores[int(worker.name) % len(cores)]
        except (TypeError, ValueError):  # a worker named otherwise: leave it unpinned
            return
        for task in os.listdir("/proc/self/task"):
            try:
                os.sched_setaffinity(int(task), {core})
            except OSError:  # a thread that ended meanwhile
                pass
