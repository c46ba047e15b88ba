"""``run_sweep``: check everything, reuse what the output folder holds, compute the rest, consolidate."""

from __future__ import annotations

import json
import os
from typing import Any, Callable, Mapping, Sequence

from ..params import ParameterError, SystemSpec
from ._analyses import make_analyses
from ._dataset import build_dataset
from ._designs import design_set
from ._execute import local_cluster, prepare_process, run_dask, run_serial
from ._store import SweepStore, design_key, sweep_identity

__all__ = ["run_sweep", "EXECUTORS"]

EXECUTORS = ("serial", "dask")


def _executor(executor: str | None, workers: Any, scheduler: Any, client: Any) -> str:
    if executor is None:
        executor = "dask" if (scheduler is not None or client is not None or workers) else "serial"
    if executor not in EXECUTORS:
        raise ParameterError(f"executor = {executor!r} is not one of {EXECUTORS}")
    if executor == "serial" and (scheduler is not None or client is not None):
        raise ParameterError("executor = 'serial' runs in this process: it takes no scheduler or client")
    if scheduler is not None and client is not None:
        raise ParameterError("give a scheduler address or a client, not both")
    if scheduler is not None and not (isinstance(scheduler, str) and scheduler.strip()):
        raise ParameterError(f"scheduler must be an address such as 'tcp://host:8786', got {scheduler!r}")
    if workers is not None:
        from .. import limits

        limits.Range("workers", 1, 4096, integer=True, what="worker processes of the local cluster").check(workers)
        if executor == "dask" and (scheduler is not None or client is not None):
            raise ParameterError("workers sets the size of a local cluster; an existing cluster (scheduler or "
                                 "client) keeps its own workers")
    return executor


def run_sweep(base: SystemSpec, grid: Mapping[str, Sequence[Any]] | None = None, *,
              designs: Sequence[Mapping[str, Any]] | None = None, analyses: Any = ("equilibria",),
              out: str | os.PathLike | None = None, executor: str | None = None, workers: int | None = None,
              scheduler: str | None = None, client: Any = None, retry_failed: bool = False, progress: bool = True,
              compilation_cache: bool = True, on_record: Callable[[dict[str, Any]], Any] | None = None) -> Any:
    """Run analyses on many designs of a rotor-bearing system; returns an ``xarray.Dataset``.

    Args:
        base: the system every design starts from (its grid ``Nx``, ``Nz`` and the analyses' collocation ``N``,
            ``m`` stay fixed unless swept, so that one compilation serves every design).
        grid: ``{field: values}`` over any :class:`SystemSpec` fields; the designs are the outer product (first
            field slowest).  Or
        designs: an explicit list of ``{field: value}`` dicts.  Exactly one of ``grid`` and ``designs``.
        analyses: names (``"static"``, ``"equilibria"``, ``"cycles"``, ``"energy"``, ``"optimum"``, also as one
            comma-separated string) for default settings, or instances (:class:`Static`, :class:`Equilibria`,
            :class:`Cycles`, :class:`Energy`, :class:`Optimum`) with their own.
        out: output folder (created): each finished design goes to ``out/designs/<key>.json`` at once, the
            Dataset to ``out/sweep.nc``; designs already there are reused (see :mod:`gfbjax.sweep._store`).
            None: nothing is written and nothing reused.
        executor: ``"serial"`` (this process, one design after another) or ``"dask"``; default ``"dask"`` when
            ``workers``, ``scheduler`` or ``client`` is given, else ``"serial"``.
        workers: worker processes of the local Dask cluster (``distributed.LocalCluster(n_workers=workers,
            threads_per_worker=1, processes=True)``; default ``os.cpu_count()``).
        scheduler: address of a running Dask scheduler (``"tcp://host:8786"``) to use instead.
        client: a ``distributed.Client`` to use instead (kept open).
        retry_failed: compute again the stored designs whose analyses raised (``outcome`` ``"failed"`` or
            ``"partial"``); by default they are reused like the others.
        progress: a tqdm bar counting finished designs (reused ones are counted at the start, not as work).
        compilation_cache: turn on JAX's persistent compilation cache in every process that computes
            (:func:`gfbjax._process.enable_compilation_cache`).
        on_record: called on this process with each design's record as it is stored.

    Returns:
        Dataset with dimensions the swept fields (grid; their values as coordinates) or ``design`` (list; each
        set field as a coordinate along it), plus ``<analysis>_omega_bar`` for the figures of the analyses at
        given speeds.  Data variables: every figure of every analysis (NaN, or ``""`` for text, where undefined
        or where the analysis raised), each with ``units``, ``long_name`` and ``analysis`` attributes;
        ``outcome`` (``"ok"``, ``"partial"``, ``"failed"``), ``message`` (which analysis raised and why),
        ``seconds``, ``design_key``.  Attributes: ``base_spec`` (JSON), ``analyses`` and ``analyses_settings``
        (JSON), ``units`` (JSON, per variable), ``gfbjax_version``, ``designs_kind``, ``swept_fields``, counts of
        designs (``n_designs``, ``n_failed``, ``n_partial``, ``n_reused``, ``n_computed``), ``executor``.

    Raises:
        ParameterError: before any computation, for an unknown field or a value out of range (naming the field
            and its allowed values), bad analysis settings, a design an analysis cannot take (e.g. cycles of a
            balanced rotor), a bad executor option, or an output folder that holds another sweep.
    """
    ds_designs = design_set(base, grid, designs)
    items = make_analyses(analyses)
    labels = [f"design {c}" for c in ds_designs.changes]
    for a in items:
        a.check(ds_designs.specs, labels)
    executor = _executor(executor, workers, scheduler, client)
    settings = [a.settings() for a in items]
    store = SweepStore(out, sweep_identity(base, settings)) if out is not None else None

    keys = [design_key(s, settings) for s in ds_designs.specs]
    records: dict[str, dict[str, Any]] = {}
    if store is not None:
        for k in dict.fromkeys(keys):
            rec = store.load(k)
            if rec is not None and not (retry_failed and rec.get("outcome") != "ok"):
                records[k] = rec
    n_reused = len(records)
    tasks, queued = [], set()
    for k, spec, changes in zip(keys, ds_designs.specs, ds_designs.changes):
        if k not in records and k not in queued:
            tasks.append((k, spec.to_dict(), changes))
            queued.add(k)
    if store is not None:
        from .. import __version__

        store.write_manifest({"gfbjax_version": __version__, "designs": ds_designs.to_json(),
                              "keys": keys})

    from tqdm.auto import tqdm

    total = len(records) + len(tasks)
    bar = tqdm(total=total, initial=n_reused, unit="design", desc="sweep", disable=not progress, dynamic_ncols=True)
    failed = [0]

    def keep(rec: dict[str, Any]) -> None:
        if store is not None and not rec.get("lost"):
            store.save(rec)
        records[rec["key"]] = rec
        failed[0] += rec["outcome"] != "ok"
        bar.update(1)
        if failed[0]:
            bar.set_postfix_str(f"{failed[0]} failed or partial", refresh=False)
        if on_record is not None:
            on_record(rec)

    try:
        if tasks and executor == "serial":
            if compilation_cache:
                prepare_process()
            run_serial(tasks, items, keep, compilation_cache)
        elif tasks:
            _on_dask(tasks, items, keep, workers, scheduler, client, compilation_cache)
    finally:
        bar.close()

    ordered = [records[k] for k in keys]
    attrs = {"base_spec": json.dumps(base.to_dict()), "executor": executor, "n_reused": n_reused,
             "n_computed": len(tasks)}
    result = build_dataset(ds_designs, items, ordered, attrs)
    if store is not None:
        store.write_dataset(result)
    return result


def _on_dask(tasks, items, keep, workers, scheduler, client, compilation_cache) -> None:
    from distributed import Client

    own_cluster = own_client = None
    try:
        if client is None:
            if scheduler is not None:
                try:
                    client = own_client = Client(scheduler, timeout="20s")
                except (OSError, TimeoutError) as exc:
                    raise ParameterError(f"scheduler = {scheduler!r}: cannot connect ({exc})") from None
            else:
                own_cluster = local_cluster(workers)
                client = own_client = Client(own_cluster)
        run_dask(tasks, items, keep, client, compilation_cache)
    finally:
        if own_client is not None:
            own_client.close()
        if own_cluster is not None:
            own_cluster.close()
