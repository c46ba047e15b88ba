"""Running the designs of a sweep: one task per design, in this process or on dask.distributed.

The task (:func:`compute_design`) runs every analysis of one design and returns a JSON-able record; an analysis
that raises is recorded there (``outcome``, ``message``), so the task itself only fails when its process dies.  The
caller stores each record the moment it arrives (``on_record``), so what is finished is on disk whatever happens
to the rest.

On Dask, records come back to the client as the futures complete (``distributed.as_completed``); a worker that
dies takes its task with it, and the scheduler gives that task to another worker, so a killed worker costs time,
not results.  A task that kills every worker it lands on (by default 3 of them) comes back as ``KilledWorker``;
that design is reported failed and not stored, so the next run retries it.
"""

from __future__ import annotations

import os
import socket
import time
import traceback
import uuid
from typing import Any, Callable, Sequence

__all__ = ["compute_design", "prepare_process", "run_serial", "run_dask", "local_cluster"]

_prepared = False


def prepare_process() -> None:
    """gfbjax's process settings in the process that computes (a Dask worker or this one), once.

    Importing gfbjax (done by importing this module) already applied :func:`gfbjax._process.configure_process`,
    before JAX started, and 64-bit mode; the persistent compilation cache is turned on here, so that every worker
    after the first loads the kernels the first one compiled instead of compiling them again."""
    global _prepared
    if _prepared:
        return
    from .._process import enable_compilation_cache

    enable_compilation_cache()
    _prepared = True


def compute_design(key: str, spec_fields: dict[str, Any], changes: dict[str, Any], analyses: Sequence[Any],
                   compilation_cache: bool = True) -> dict[str, Any]:
    """Run ``analyses`` on the system ``SystemSpec(**spec_fields)``; the unit of work of a sweep.

    Returns the record stored for the design: ``key``, ``changes``, ``spec``, ``analyses`` (settings),
    ``figures`` ({figure name: value, or a list over the analysis' speeds}), ``outcome`` (``"ok"``; ``"partial"``
    when some analyses raised; ``"failed"`` when all did), ``message`` (one line per analysis that raised:
    ``"cycles: NoSolutionError: ..."``), ``seconds``, ``host``, ``pid``.  The figures of an analysis that raised
    are left out (NaN in the Dataset).  KeyboardInterrupt is not caught.
    """
    if compilation_cache:
        prepare_process()
    from ..params import SystemSpec

    spec = SystemSpec(**spec_fields)
    t0 = time.perf_counter()
    figures: dict[str, Any] = {}
    errors: list[str] = []
    for analysis in analyses:
        try:
            figures.update(analysis.run(spec))
        except Exception as exc:  # noqa: BLE001 - one design's failure is a result of the sweep, not its end
            text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
            where = traceback.extract_tb(exc.__traceback__)[-1] if exc.__traceback__ else None
            at = f" (at {os.path.basename(where.filename)}:{where.lineno})" if where else ""
            errors.append(f"{analysis.name}: {type(exc).__name__}: {text}{at}")
    outcome = "ok" if not errors else ("failed" if len(errors) == len(analyses) else "partial")
    return {"key": key, "changes": dict(changes), "spec": dict(spec_fields),
            "analyses": [a.settings() for a in analyses], "figures": figures, "outcome": outcome,
            "message": "; ".join(errors), "seconds": time.perf_counter() - t0, "host": socket.gethostname(),
            "pid": os.getpid()}


def lost_record(key: str, spec_fields: dict[str, Any], changes: dict[str, Any], analyses: Sequence[Any],
                exc: BaseException) -> dict[str, Any]:
    """The record of a design whose task itself failed (its worker died too often): failed, not to be stored."""
    return {"key": key, "changes": dict(changes), "spec": dict(spec_fields),
            "analyses": [a.settings() for a in analyses], "figures": {}, "outcome": "failed",
            "message": f"task lost: {type(exc).__name__}: {str(exc).strip()[:300]}", "seconds": float("nan"),
            "host": "", "pid": -1, "lost": True}


Task = tuple[str, dict[str, Any], dict[str, Any]]  # key, spec fields, changes
OnRecord = Callable[[dict[str, Any]], None]


def run_serial(tasks: Sequence[Task], analyses: Sequence[Any], on_record: OnRecord,
               compilation_cache: bool = True) -> None:
    """Compute the tasks one after another in this process."""
    for key, fields, changes in tasks:
        on_record(compute_design(key, fields, changes, analyses, compilation_cache))


def local_cluster(n_workers: int | None = None, pin: bool | None = None) -> Any:
    """A ``distributed.LocalCluster`` of ``n_workers`` single-threaded worker processes (default: one per CPU
    core).  One thread per process: XLA:CPU already spreads one design's kernels over the cores, and JAX's
    compiled kernels and the jit caches are per process anyway.  No dashboard (no port to collide with).

    ``pin`` (default: with 2 workers or more, and no more workers than cores) binds worker ``i`` to core ``i`` (see
    :class:`gfbjax.sweep._pinning.PinToCore`).  The workers' statistical profiler is off."""
    import dask
    from distributed import LocalCluster

    from ._pinning import PinToCore

    n = n_workers or os.cpu_count() or 1
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    # one worker keeps every core (XLA spreads its kernels over them); more than one core each: nothing to bind
    plugins = {PinToCore()} if (pin if pin is not None else 2 <= n <= cores) else set()
    # Dask's statistical profiler samples every worker thread's stack every 10 ms; on JAX's deep stacks that cost
    # 7-13 % of each design (the 16-design sweep of benchmarks/sweep_dask.py) for a profile nobody reads here
    with dask.config.set({"distributed.worker.profile.enabled": False}):
        return LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                            plugins=plugins)


def run_dask(tasks: Sequence[Task], analyses: Sequence[Any], on_record: OnRecord, client: Any,
             compilation_cache: bool = True) -> None:
    """Compute the tasks on a ``distributed.Client``: one task per design, records handled on the client as the
    futures complete.  A task that failed as a whole (``KilledWorker``: its workers kept dying) gives a failed
    record marked ``lost``.  On KeyboardInterrupt the pending futures are cancelled."""
    from distributed import as_completed

    run = uuid.uuid4().hex[:8]
    futures = {}
    for key, fields, changes in tasks:
        # the key names the design: the scheduler's logs and client.processing() say which design a worker holds
        fut = client.submit(compute_design, key, fields, changes, list(analyses), compilation_cache,
                            key=f"gfbjax-sweep-{key}-{run}", pure=False, retries=0)
        futures[fut] = (key, fields, changes)
    try:
        for fut in as_completed(list(futures)):
            key, fields, changes = futures.pop(fut)
            try:
                rec = fut.result()
            except Exception as exc:  # noqa: BLE001 - the task itself was lost (KilledWorker, a dead cluster)
                rec = lost_record(key, fields, changes, analyses, exc)
            fut.release()
            on_record(rec)
    except BaseException:
        client.cancel(list(futures))
        raise
