"""Benchmark (b): a whole limit-cycle branch of the reference system, Omega_bar 0.05 -> 1.0, on the default grid.

What a user runs with ``gfbjax cycles``: collocation (N=16, m=4), pseudo-arclength steps, Floquet multipliers at
every point, LPC/PD/NS detection and localisation.  Compilation is measured apart, in the same process: a first,
short branch (3 points: the time to the first points of a new process), then the whole branch once, which compiles
what only later points need (the localisation's and its error estimate's kernels on the halved mesh; until
session 16 these ~2-4 s were inside the timed branch), then the timed branch.

For the ratio, one Newton iteration of the dense condensation is timed on the same orbit: the cost per Newton
iteration a branch would pay without the sparse solver.  It is measured through the one Newton corrector
(``cont.bind_solver`` with ``cont.DenseCondensation()``, ``correct`` limited to one step, which evaluates twice:
at the guess and at the new iterate; each evaluation is a linearisation and the solve for step and tangent), as
the correction's time over its evaluations.

Usage:  python benchmarks/cycle_branch.py [--nx 48 --nz 8] [--start 0.05 --end 1.0] [--dlam-max D] [--chord-tol T]
        [--no-dense]
Writes benchmarks/results/cycle_branch.json and prints a table, with the sparse solver's work in the timed branch
(``WorkCount``: interval blocks factorised and interval solves; unlike the times, the same in every run).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import gfbjax  # noqa: F401  (process defaults: XLA flags, x64) before any JAX work
import jax
import numpy as np

from gfbjax import cont
from gfbjax.analyses.cycles import (CYCLE_DEFAULTS, continue_gfb_cycles, default_cycle_settings, gfb_cycle_problem,
                                    linear_response_start)

RESULTS = Path(__file__).resolve().parent / "results"


class WorkCount:
    """Counts the sparse solver's work while active: SuperLU factorisations of interval blocks and interval solves
    (right-hand-side columns, each one triangular solve pair with one block).  Unlike wall time on a shared machine,
    these counts do not change from run to run, so they compare two versions of the engine exactly; the time per
    solve and per factorisation is then a property of the machine.  Wraps ``scipy.sparse.linalg.splu`` as the
    solver module sees it (benchmark instrumentation only; the engine is unchanged)."""

    def __init__(self) -> None:
        self.factorisations, self.solve_columns = 0, 0

    def __enter__(self) -> "WorkCount":
        from types import SimpleNamespace

        from gfbjax.cont import _sparse

        count, real = self, _sparse.spla

        class Counted:
            def __init__(self, lu):
                self._lu = lu

            def solve(self, b, trans="N"):
                count.solve_columns += 1 if np.ndim(b) == 1 else np.shape(b)[1]
                return self._lu.solve(b, trans=trans)

            def __getattr__(self, name):
                return getattr(self._lu, name)

        def splu(*args, **kwargs):
            count.factorisations += 1
            return Counted(real.splu(*args, **kwargs))

        self._module, self._real = _sparse, real
        _sparse.spla = SimpleNamespace(splu=splu)
        return self

    def __exit__(self, *exc) -> None:
        self._module.spla = self._real


def add_branch_arguments(ap: argparse.ArgumentParser) -> None:
    """The reference branch's grid, speed range and point placement (also used by point_placement.py)."""
    ap.add_argument("--nx", type=int, default=48)
    ap.add_argument("--nz", type=int, default=8)
    ap.add_argument("--start", type=float, default=0.05)
    ap.add_argument("--end", type=float, default=1.0)
    ap.add_argument("--dlam-max", type=float, default=CYCLE_DEFAULTS["dlam_max"])
    ap.add_argument("--chord-tol", type=float, default=CYCLE_DEFAULTS["chord_tol"],
                    help="point placement (inf: steps set by --dlam-max and the arclength steps alone)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    add_branch_arguments(ap)
    ap.add_argument("--m", type=int, default=4, help="collocation points per interval")
    ap.add_argument("--N", type=int, default=16, help="mesh intervals")
    ap.add_argument("--collocation", choices=("gauss", "radau"), default=None,
                    help="collocation points (default: that of default_cycle_settings)")
    ap.add_argument("--no-dense", action="store_true", help="skip the dense-condensation reference iteration")
    ap.add_argument("--out", default=str(RESULTS / "cycle_branch.json"))
    a = ap.parse_args()

    params = gfbjax.reference_system(Nx=a.nx, Nz=a.nz).nondim()
    prob = gfb_cycle_problem(params)
    extra = {} if a.collocation is None else {"collocation": a.collocation}
    extra["chord_tol"] = a.chord_tol
    settings = default_cycle_settings(dlam_max=a.dlam_max, m=a.m, N=a.N, **extra)

    t0 = time.perf_counter()
    warm = continue_gfb_cycles(params, a.start, a.end, default_cycle_settings(dlam_max=a.dlam_max, m=a.m, N=a.N, max_points=3,
                                                                          **extra))
    t_compile = time.perf_counter() - t0
    assert len(warm) == 3, f"{warm.outcome}: {warm.message}"

    t0 = time.perf_counter()
    continue_gfb_cycles(params, a.start, a.end, settings)
    t_first = time.perf_counter() - t0

    with WorkCount() as work:
        t0 = time.perf_counter()
        branch = continue_gfb_cycles(params, a.start, a.end, settings)
        t_branch = time.perf_counter() - t0

    special = [{"type": s.type, "Omega_bar": float(s.lam), "rpm": gfbjax.reference_system().rpm(float(s.lam)),
                "located": bool(s.located), "angle": None if s.angle is None else float(s.angle),
                "Omega_bar_error": None if not np.isfinite(s.lam_error) else float(s.lam_error)}
               for s in branch.special]
    rec = {
        "system": "reference", "Nx": a.nx, "Nz": a.nz, "n": prob.n, "N": settings.N, "m": settings.m,
        "range": [a.start, a.end], "dlam_max": a.dlam_max,
        "chord_tol": a.chord_tol if np.isfinite(a.chord_tol) else "inf", "reached": float(branch.lam[-1]),
        "outcome": str(branch.outcome), "message": branch.message,
        "points": len(branch), "newton_iterations": int(np.sum(branch.newton_iterations)),
        "factorisations": work.factorisations, "interval_solves": work.solve_columns,
        "compile_and_first_3_points_s": round(t_compile, 2), "first_full_run_s": round(t_first, 2),
        "branch_s": round(t_branch, 2),
        "per_point_s": round(t_branch / len(branch), 3),
        "max_trivial_error": float(np.max(branch.trivial_error)), "special": special,
        "collocation": settings.collocation, "flagged_points": int(np.sum(branch.flagged)),
        "max_stiff_modulus": float(np.max(branch.stiff_modulus)),
        "max_multiplier_error": float(np.max(branch.multiplier_error)),
        "max_mesh_error": float(np.max(branch.mesh_error)),
        "multiplier_error_by_speed": [[round(float(l), 4), float(f"{v:.2e}")]
                                      for l, v in zip(branch.lam, branch.multiplier_error)],
        "stiff_modulus_by_speed": [[round(float(l), 4), round(float(v), 4)]
                                   for l, v in zip(branch.lam, branch.stiff_modulus)],
        "machine": {"cpus": os.cpu_count(), "platform": platform.platform()},
        "versions": {"jax": jax.__version__},
        "note": "wall times on a shared 2-core machine; other processes may have run at the same time",
    }
    if not a.no_dense:
        x_of_t, T, _ = linear_response_start(params, 0.3)
        sch = cont.Scheme(settings.m)
        o = cont.orbit_from_function(x_of_t, T, 0.3, sch, cont.uniform_mesh(settings.N))
        con = cont.natural_constraint(o, 0.3)
        dense = cont.bind_solver(prob, sch, cont.CycleSettings(linear_solver=cont.DenseCondensation()))
        one_step = cont.NewtonSettings(max_iter=1)

        def dense_step() -> int:
            """One dense Newton step from o; returns the evaluations (linearisations) it made."""
            sol, _ = dense.correct(o, con, one_step)
            jax.block_until_ready(sol.x)
            return int(sol.iterations) + 1

        t0 = time.perf_counter()
        dense_step()
        tc = time.perf_counter() - t0
        t0 = time.perf_counter()
        evals = dense_step()
        rec["dense_iteration_s"] = round((time.perf_counter() - t0) / evals, 2)
        rec["dense_compile_and_first_s"] = round(tc, 2)  # compilation and the first one-step correction
        rec["sparse_iterations_per_point"] = round(rec["newton_iterations"] / len(branch), 2)

    print(f"{'quantity':<44} value")
    rows = [("grid (n)", f"{a.nx}x{a.nz} ({prob.n})"), ("points", rec["points"]),
            ("Omega_bar reached", f"{rec['reached']:.4f}"), ("compile + 3 points [s]", rec["compile_and_first_3_points_s"]),
            ("first whole branch (rest of compilation) [s]", rec["first_full_run_s"]),
            ("branch after compilation [s]", rec["branch_s"]), ("per point [s]", rec["per_point_s"]),
            ("Newton iterations (all points)", rec["newton_iterations"]),
            ("interval blocks factorised (SuperLU)", rec["factorisations"]),
            ("interval solves (right-hand-side columns)", rec["interval_solves"]),
            ("max |mu_trivial - 1|", f"{rec['max_trivial_error']:.2e}"),
            ("collocation points", rec["collocation"]),
            ("spurious multipliers up to |mu| (stiff_modulus)", f"{rec['max_stiff_modulus']:.3f}"),
            ("max multiplier error (frozen, mode defects, halved)", f"{rec['max_multiplier_error']:.1e}"),
            ("max mesh error of the orbits (relative)", f"{rec['max_mesh_error']:.1e}"),
            ("flagged points", rec["flagged_points"])]
    rows += [(f"{s['type']} at", f"Omega_bar {s['Omega_bar']:.5f}"
              + ("" if s["Omega_bar_error"] is None else f" +- {s['Omega_bar_error']:.0e}") + f" ({s['rpm']:.0f} rpm)")
             for s in special]
    if "dense_iteration_s" in rec:
        rows.append(("dense condensation, one Newton iteration [s]", rec["dense_iteration_s"]))
        est = rec["dense_iteration_s"] * (rec["newton_iterations"] + len(branch))
        rec["dense_branch_estimate_s"] = round(est, 1)
        rows.append(("dense: same branch, lower bound [s]", f"{est:.0f} ({est / t_branch:.0f}x)"))
    for k, v in rows:
        print(f"{k:<44} {v}")
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(rec, indent=1))
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
