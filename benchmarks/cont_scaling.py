"""Cost of one condensed Newton step (linearisation + condensation + block
elimination, two right-hand sides) and of the stable Floquet computation
versus the number of mesh intervals N and the state dimension n.

The step is one iteration of the Newton corrector on the dense condensation
(``cont.bind_solver(..., CycleSettings(linear_solver=cont.DenseCondensation()))``):
each iteration evaluates the residual and solves the condensed system for the
Newton step and the tangent (two right-hand sides, one factorisation).  A
correction limited to one step (``NewtonSettings(max_iter=1)``) makes two such
evaluations (the step, then the check at the new iterate); the reported step
time is the correction's time over its evaluations.  Floquet: the periodic QR
iteration (``cont.multipliers_periodic``) on the transfer matrices.

Usage:  python benchmarks/cont_scaling.py --n 20 --N 10 20 40 80 [--m 4] [--repeat 3] [--floquet]
Prints one JSON line per (n, N): first-call (compile) time, step time (min over repeats), Floquet time.
Expected: step time ~ linear in N (O(N n^3)), never the dense (N m n)^2 matrix.
"""
import argparse
import json
import os
import time

# multi-threaded OpenBLAS on a small/shared machine makes the many small LAPACK
# calls ~1000x slower; override from the environment if you want threads.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import gfbjax  # noqa: E402,F401  (x64 and the XLA:CPU process settings before any JAX work)
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from gfbjax import cont  # noqa: E402

# one Newton step: the corrector evaluates at the guess, steps, and evaluates once more at the new iterate
ONE_STEP = cont.NewtonSettings(max_iter=1)
DENSE = cont.CycleSettings(linear_solver=cont.DenseCondensation())


def field(x, lam, A):
    """Stiff synthetic field: linear part with decay rates up to ~1e3 plus a cubic term."""
    return A @ x - x * jnp.sum(x * x) / x.shape[0] + lam * x


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--n", type=int, nargs="+", default=[20])
    p.add_argument("--N", type=int, nargs="+", default=[10, 20, 40, 80])
    p.add_argument("--m", type=int, default=4)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--floquet", action="store_true")
    a = p.parse_args()
    sch = cont.Scheme(a.m)
    for n in a.n:
        rng = np.random.default_rng(0)
        S, _ = np.linalg.qr(rng.normal(size=(n, n)))
        A = jnp.asarray(S @ np.diag(-np.logspace(0, 3, n)) @ S.T)
        bound = cont.bind_solver(cont.CycleProblem(f=field, n=n, args=A), sch, DENSE)
        for N in a.N:
            o = cont.orbit_from_function(lambda t: np.cos(2 * np.pi * t)[:, None] * np.linspace(1, 2, n)[None],
                                         1.0, 0.0, sch, cont.uniform_mesh(N))
            con = cont.natural_constraint(o, 0.0)

            def step() -> int:
                """One corrector step; returns the number of linearisations (evaluations) it made."""
                sol, _ = bound.correct(o, con, ONE_STEP)
                jax.block_until_ready(sol.x)
                return int(sol.iterations) + 1

            t0 = time.perf_counter()
            evals = step()
            tc = time.perf_counter() - t0
            ts = []  # min of repeats: robust to other load on the machine
            for _ in range(a.repeat):
                t0 = time.perf_counter()
                evals = step()
                ts.append((time.perf_counter() - t0) / evals)
            rec = {"backend": jax.default_backend(), "n": n, "N": N, "m": a.m, "first_call_s": round(tc, 3),
                   "step_s": round(float(np.min(ts)), 5)}
            if a.floquet:
                G = bound.linearise(o, con).transfer_matrices()
                t0 = time.perf_counter()
                r = cont.multipliers_periodic(G)
                rec.update(floquet_s=round(time.perf_counter() - t0, 3), floquet_sweeps=r.sweeps)
            print(json.dumps(rec), flush=True)


if __name__ == "__main__":
    main()
