"""Cost of one condensed Newton step (linearisation + condensation + block
elimination, two right-hand sides) and of the stable Floquet computation
versus the number of mesh intervals N and the state dimension n.

Usage:  python benchmarks/cont_scaling.py --n 20 --N 10 20 40 80 [--m 4] [--repeat 3]
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

import gfbjax.cont  # noqa: F401  (sets the XLA:CPU scheduler workaround before JAX starts)
import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from gfbjax.cont import collocation as col  # noqa: E402
from gfbjax.cont import floquet  # noqa: E402


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
    sch = col.Scheme(a.m)
    for n in a.n:
        rng = np.random.default_rng(0)
        S, _ = np.linalg.qr(rng.normal(size=(n, n)))
        A = jnp.asarray(S @ np.diag(-np.logspace(0, 3, n)) @ S.T)
        for N in a.N:
            o = col.orbit_from_function(lambda t: np.cos(2 * np.pi * t)[:, None] * np.linspace(1, 2, n)[None],
                                        1.0, 0.0, sch, col.uniform_mesh(N))
            con = col.natural_constraint(o, 0.0)
            t0 = time.perf_counter()
            jax.block_until_ready(col._step_and_tangent(field, A, o, con, sch))
            tc = time.perf_counter() - t0
            ts = []  # min of repeats: robust to other load on the machine
            for _ in range(a.repeat):
                t0 = time.perf_counter()
                jax.block_until_ready(col._step_and_tangent(field, A, o, con, sch))
                ts.append(time.perf_counter() - t0)
            rec = {"backend": jax.default_backend(), "n": n, "N": N, "m": a.m, "first_call_s": round(tc, 3),
                   "step_s": round(float(np.min(ts)), 5)}
            if a.floquet:
                G = np.asarray(col.transfer_matrices(field, A, o, sch))
                t0 = time.perf_counter()
                r = floquet.multipliers_periodic(G)
                rec.update(floquet_s=round(time.perf_counter() - t0, 3), floquet_sweeps=r.sweeps)
            print(json.dumps(rec), flush=True)


if __name__ == "__main__":
    main()
