"""Benchmark (c): time per collocation Newton iteration against the state count n and the mesh intervals N.

One Newton iteration = residual + linearisation (Jacobian at the N*m Gauss points) + solution of the bordered
collocation system.  Two linear solvers on the same GFB orbit (the linear forced response at Omega_bar = 0.3):

* ``sparse`` (``cont.SparseSweep()``): coloured Jacobian values, per-interval sparse LU, GMRES on the
  n + 2 reduced unknowns; also the Arnoldi Floquet multipliers (``cont.Arnoldi(k=12)``, 12 largest);
* ``dense`` (``cont.DenseCondensation()``): condensation of parameters by batched dense QR, O(N (mn)^3); only
  where it takes less than ``--dense-max-n`` states.

Both are timed through the one Newton corrector, ``cont.bind_solver(problem, scheme, settings).correct(...)``,
limited to one step (``NewtonSettings(max_iter=1)``): it evaluates twice (at the guess, then at the new iterate:
residual, linearisation and solve each time), and the iteration time is the correction's time over its
evaluations.  The dense evaluation also solves for the tangent (a second right-hand side of the same
factorisation), the sparse one does not (its tangent is one more GMRES solve after convergence only).  The
linearisation alone (``bound.linearise``: the factorised interval blocks) is timed for the sparse solver.

Growth with N should be linear for both (per-interval work); growth with n is ~n^3 for dense, far less for sparse.

Usage:  python benchmarks/newton_scaling.py [--grids 16x2 24x3 32x4 48x8 64x8 80x8] [--N 8 16 32 64]
Writes benchmarks/results/newton_scaling.json and prints a table.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path
from typing import Callable

import gfbjax  # noqa: F401  (process defaults before any JAX work)
import jax
import numpy as np

from gfbjax import cont
from gfbjax.analyses.cycles import gfb_cycle_problem, linear_response_start

RESULTS = Path(__file__).resolve().parent / "results"
OMEGA = 0.3
ONE_STEP = cont.NewtonSettings(max_iter=1)  # one Newton step: two evaluations (guess, new iterate)
N_MULTIPLIERS = 12


def _best(fn, repeat: int) -> float:
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return float(np.min(ts))  # min over repeats: robust to other load on the machine


def _best_of(timer: Callable[[], float], repeat: int) -> float:
    """Minimum over ``repeat`` calls of a function that returns its own time."""
    return float(min(timer() for _ in range(repeat)))


def _per_iteration(bound, o: cont.Orbit, con: cont.Constraint) -> Callable[[], float]:
    """A timer of one Newton iteration with ``bound``: one corrector step from ``o``, time over evaluations."""
    def run() -> float:
        t0 = time.perf_counter()
        sol, _ = bound.correct(o, con, ONE_STEP)
        jax.block_until_ready(sol.x)
        return (time.perf_counter() - t0) / (int(sol.iterations) + 1)
    return run


def measure(nx: int, nz: int, N: int, m: int, repeat: int, dense: bool) -> dict:
    params = gfbjax.reference_system(Nx=nx, Nz=nz).nondim()
    prob = gfb_cycle_problem(params)
    sch = cont.Scheme(m)
    x_of_t, T, _ = linear_response_start(params, OMEGA)
    o = cont.orbit_from_function(x_of_t, T, OMEGA, sch, cont.uniform_mesh(N))
    con = cont.natural_constraint(o, OMEGA)
    sp = cont.bind_solver(prob, sch, cont.CycleSettings(linear_solver=cont.SparseSweep()))
    sparse_iter = _per_iteration(sp, o, con)
    sparse_iter()  # compile
    lin = sp.linearise(o, con)  # the factorised blocks at o, as continuation keeps them for the multipliers
    rec = {"grid": f"{nx}x{nz}", "n": prob.n, "N": N, "m": m,
           "sparse_linearise_s": _best(lambda: sp.linearise(o, con), repeat),
           "sparse_iteration_s": _best_of(sparse_iter, repeat),
           "sparse_multipliers_s": _best(lambda: cont.Arnoldi(k=N_MULTIPLIERS).multipliers(lin, {}), 1),
           "colors": cont.color_pattern(prob.jac_sparsity).n_colors}
    if dense:
        step = _per_iteration(cont.bind_solver(prob, sch, cont.CycleSettings(linear_solver=cont.DenseCondensation())),
                              o, con)
        step()  # compile
        rec["dense_iteration_s"] = _best_of(step, max(1, repeat // 2))
    return rec


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--grids", nargs="+", default=["16x2", "24x3", "32x4", "48x8", "64x8", "80x8"])
    ap.add_argument("--N", type=int, nargs="+", default=[8, 16, 32, 64])
    ap.add_argument("--m", type=int, default=4)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--dense-max-n", type=int, default=200)
    ap.add_argument("--out", default=str(RESULTS / "newton_scaling.json"))
    a = ap.parse_args()
    rows = []
    print(f"{'grid':>6} {'n':>5} {'N':>4} {'sparse iter [s]':>16} {'of which lin.':>14} {'multipliers':>12} "
          f"{'dense iter [s]':>15}")
    jobs = [(g, 16) for g in a.grids] + [("48x8", N) for N in a.N if N != 16]
    for g, N in jobs:
        nx, nz = (int(v) for v in g.split("x"))
        n_est = (nx * nz + nx + 6 + 2)
        r = measure(nx, nz, N, a.m, a.repeat, dense=n_est <= a.dense_max_n)
        rows.append(r)
        d = r.get("dense_iteration_s")
        print(f"{r['grid']:>6} {r['n']:>5} {N:>4} {r['sparse_iteration_s']:>16.3f} {r['sparse_linearise_s']:>14.3f} "
              f"{r['sparse_multipliers_s']:>12.3f} {('%.3f' % d) if d else '-':>15}", flush=True)
    byN = sorted((r for r in rows if r["grid"] == "48x8"), key=lambda r: r["N"])
    if len(byN) >= 2:
        slope = np.polyfit(np.log([r["N"] for r in byN]), np.log([r["sparse_iteration_s"] for r in byN]), 1)[0]
        print(f"growth with N at 48x8: time ~ N^{slope:.2f}")
    else:
        slope = None
    out = {"omega": OMEGA, "rows": rows, "growth_exponent_in_N": slope,
           "machine": {"cpus": os.cpu_count(), "platform": platform.platform()},
           "note": "min over repeats; shared 2-core machine"}
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(out, indent=1))
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
