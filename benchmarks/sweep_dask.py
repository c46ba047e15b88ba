"""A 16-design sweep (4 alpha_f x 4 eta; the Hopf speed from the equilibria branch plus a short unbalance-response
cycle branch per design) run serially in this process and on a local Dask cluster of 2 single-threaded worker
processes, each bound to its own core (gfbjax.sweep.run_sweep); and, for comparison, W_cb over a small foil grid
by the vmapped batch (gfbjax.design.maps.energy_map) and by a Python loop (energy_map_loop).  The serial sweep is
also run with this process bound to one core: what one pinned worker can do, so the bound on the speed-up.

Order, so that compilation is not counted as sweep time: one design is computed first in this process (compiles
the kernels and fills the persistent compilation cache); the serial sweep then reuses this process's compiled
kernels; the cluster is started (timed on its own) and its workers load the kernels from the persistent cache on
their first design (counted in the Dask sweep: a fresh worker always pays it).  Both sweeps must give the same
numbers (checked to 1e-10).

Usage:  python benchmarks/sweep_dask.py [--nx 16 --nz 2] [--workers 2] [--cycle-points 10]
        [--cycle-range 0.3 0.45] [--no-maps] [--quick]
Writes benchmarks/results/sweep_dask.json (``--quick``: a 2 x 2 grid, no maps, a check that the script runs; give
it another ``--out``).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import gfbjax
from gfbjax.sweep import Cycles, Equilibria, local_cluster, run_sweep

RESULTS = Path(__file__).resolve().parent / "results"
ALPHA_F = [0.05, 0.1, 0.5, 1.0]
ETA = [0.02, 0.05, 0.2, 0.5]
FIGURES = ("hopf_omega_bar", "hopf_whirl_ratio", "cycles_loss_omega_bar", "cycles_points")


def _cpu_seconds() -> float:
    """CPU time of this process, all its threads, user + system [s]."""
    import resource

    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _one_core_child(a) -> None:
    """(Run in a child process bound to one core from its start, like a pinned worker.)  The warm-up design, then
    the serial sweep timed; prints its wall time as JSON."""
    base, analyses, grid = _setup(a)
    run_sweep(base, {"alpha_f": [0.2], "eta": [0.1]}, analyses=analyses, progress=False)
    t0 = time.perf_counter()
    run_sweep(base, grid, analyses=analyses, progress=False)
    print(json.dumps({"serial_one_core_s": time.perf_counter() - t0}))


def _serial_on_one_core(argv: list[str]) -> float | None:
    """Wall time of the serial sweep in a fresh process bound to one core before it starts (so that XLA sizes
    and places its threads as in a pinned worker; binding a running process instead leaves its thread pools
    spinning on one core, 2.6x slower on the longer designs); None where binding is not available."""
    if not hasattr(os, "sched_setaffinity"):
        return None
    core = min(os.sched_getaffinity(0))
    out = subprocess.run([sys.executable, __file__, *argv, "--one-core-child"], capture_output=True, text=True,
                         preexec_fn=lambda: os.sched_setaffinity(0, {core}), check=True)
    return float(json.loads(out.stdout.strip().splitlines()[-1])["serial_one_core_s"])


def _setup(a):
    base = gfbjax.reference_system(Nx=a.nx, Nz=a.nz)
    analyses = [Equilibria(0.05, 1.0), Cycles(*a.cycle_range, m=3, N=8, max_points=a.cycle_points, locate=False)]
    grid = {"alpha_f": ALPHA_F[:2], "eta": ETA[:2]} if a.quick else {"alpha_f": ALPHA_F, "eta": ETA}
    return base, analyses, grid


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--nx", type=int, default=16)
    ap.add_argument("--nz", type=int, default=2)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cycle-points", type=int, default=10, help="points of each design's cycle branch (default 10)")
    ap.add_argument("--cycle-range", type=float, nargs=2, default=(0.3, 0.45), metavar=("START", "END"),
                    help="Omega_bar range of each design's cycle branch (default 0.3 0.45)")
    ap.add_argument("--no-maps", action="store_true", help="skip the vmapped-batch vs loop comparison")
    ap.add_argument("--quick", action="store_true", help="2 x 2 designs and no maps: checks that the script runs")
    ap.add_argument("--out", default=str(RESULTS / "sweep_dask.json"))
    ap.add_argument("--one-core-child", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.one_core_child:
        return _one_core_child(a)
    base, analyses, grid = _setup(a)
    n = len(grid["alpha_f"]) * len(grid["eta"])
    rows: dict = {}

    t0 = time.perf_counter()
    run_sweep(base, {"alpha_f": [0.2], "eta": [0.1]}, analyses=analyses, progress=False)
    rows["warm_up_one_design_s"] = time.perf_counter() - t0

    with tempfile.TemporaryDirectory() as tmp:
        t0, cpu0 = time.perf_counter(), _cpu_seconds()
        serial = run_sweep(base, grid, analyses=analyses, out=Path(tmp) / "serial", progress=False)
        rows["serial_s"] = time.perf_counter() - t0
        # cores the serial run kept busy (XLA:CPU spreads one design's kernels over its thread pool): with c busy
        # cores of w, w processes can be at most w / c times faster
        rows["serial_busy_cores"] = (_cpu_seconds() - cpu0) / rows["serial_s"]
        # the same serial sweep in a process bound to one core: what one pinned worker does, so w pinned workers
        # can at best take serial_one_core_s / w
        one_core = _serial_on_one_core([arg for arg in sys.argv[1:] if arg != "--one-core-child"])
        if one_core is not None:
            rows["serial_one_core_s"] = one_core
            rows["bound_speedup"] = a.workers * rows["serial_s"] / one_core

        from distributed import Client

        t0 = time.perf_counter()
        cluster = local_cluster(a.workers)
        client = Client(cluster)
        client.wait_for_workers(a.workers)
        rows["cluster_start_s"] = time.perf_counter() - t0
        try:
            t0 = time.perf_counter()
            dask = run_sweep(base, grid, analyses=analyses, out=Path(tmp) / "dask", client=client, progress=False)
            rows["dask_s"] = time.perf_counter() - t0
            # the same sweep again on the same (now warm) workers, into a new folder: what every further sweep of
            # a long-lived cluster costs, without the per-process tracing and cache loading of the first design
            t0 = time.perf_counter()
            run_sweep(base, grid, analyses=analyses, out=Path(tmp) / "dask_warm", client=client, progress=False)
            rows["dask_warm_s"] = time.perf_counter() - t0
        finally:
            client.close()
            cluster.close()

    diffs = {}
    for v in FIGURES:
        x, y = np.asarray(serial[v], float), np.asarray(dask[v], float)
        same_nan = bool(np.array_equal(np.isnan(x), np.isnan(y)))
        both = np.isfinite(x) & np.isfinite(y)
        diffs[v] = float(np.max(np.abs(x - y)[both])) if both.any() else 0.0
        assert same_nan and diffs[v] <= 1e-10 * max(1.0, float(np.nanmax(np.abs(x)))), (v, diffs[v])
    rows["max_abs_difference"] = diffs
    rows["designs"] = int(serial.attrs["n_designs"])
    rows["failed_or_partial"] = int(np.sum(np.asarray(serial["outcome"]) != "ok"))
    rows["speedup"] = rows["serial_s"] / rows["dask_s"]
    rows["speedup_warm_workers"] = rows["serial_s"] / rows["dask_warm_s"]
    rows["hopf_omega_bar"] = np.asarray(serial["hopf_omega_bar"]).tolist()
    rows["cycles_loss_omega_bar"] = np.asarray(serial["cycles_loss_omega_bar"]).tolist()

    if not (a.no_maps or a.quick):
        from gfbjax.design.maps import energy_map, energy_map_loop

        p = base.nondim()
        am, em = np.array([0.05, 0.1, 0.5]), np.array([0.02, 0.2, 0.5])
        t0 = time.perf_counter()
        energy_map(p, 0.3, am, em, N=8)
        first = time.perf_counter() - t0
        batch = energy_map(p, 0.3, am, em, N=8)
        energy_map_loop(p, 0.3, am[:1], em[:1], N=8)  # compiles the loop's kernels
        loop = energy_map_loop(p, 0.3, am, em, N=8)
        rows["energy_map"] = {"points": int(batch.converged.size), "vmapped_batch_s": batch.seconds,
                              "vmapped_first_call_s": first, "loop_s": loop.seconds,
                              "batch_member_steps": batch.member_steps, "loop_steps": loop.member_steps,
                              "agree_converged": bool(np.array_equal(batch.converged, loop.converged))}

    rows["machine"] = {"cpus": os.cpu_count(), "platform": platform.platform(), "load_1min": os.getloadavg()[0],
                       "grid": [a.nx, a.nz], "workers": a.workers,
                       "cycle_points": a.cycle_points, "cycle_range": list(a.cycle_range)}
    print(f"{'run':<34} {'seconds':>9}")
    print(f"{'warm-up (1 design, compiles)':<34} {rows['warm_up_one_design_s']:>9.1f}")
    print(f"{f'serial, {n} designs':<34} {rows['serial_s']:>9.1f}   busy cores {rows['serial_busy_cores']:.2f}")
    if "serial_one_core_s" in rows:
        print(f"{'serial, bound to one core':<34} {rows['serial_one_core_s']:>9.1f}   bound for "
              f"{a.workers} pinned workers {rows['bound_speedup']:.2f}x")
    print(f"{f'Dask cluster start ({a.workers} processes)':<34} {rows['cluster_start_s']:>9.1f}")
    print(f"{f'Dask, {n} designs on {a.workers} workers':<34} {rows['dask_s']:>9.1f}   speed-up {rows['speedup']:.2f}x")
    print(f"{'  again, workers warm':<34} {rows['dask_warm_s']:>9.1f}   speed-up "
          f"{rows['speedup_warm_workers']:.2f}x")
    if "energy_map" in rows:
        m = rows["energy_map"]
        print(f"{'energy map 3x3, vmapped batch':<34} {m['vmapped_batch_s']:>9.2f}")
        print(f"{'energy map 3x3, Python loop':<34} {m['loop_s']:>9.2f}")
    print("max |serial - Dask|:", {k: f"{v:.1e}" for k, v in diffs.items()})
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(rows, indent=1) + "\n")
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
