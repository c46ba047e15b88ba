#!/usr/bin/env python
"""Grid convergence of the static equilibrium and its critical eigenvalue (foundation issue, item 6).

Picks the default finite-difference grid ``(Nx, Nz)`` of the reference system (``gfbjax.reference_system()``,
gravity load only, ``w = 0``): the candidate with the fewest states ``n = (Nx-1)*Nz + (Nx-1) + 8`` whose

* static journal position: ``max(|dx_j|, |dy_j|) / |(x_j, y_j)|`` and
* critical eigenvalue: ``|d lambda_crit| / |lambda_crit|``

are within ``--tol`` (0.5 %) of a much finer reference grid at every speed of ``--speeds``.  The critical
eigenvalue is the Jacobian's eigenvalue with the largest real part (the rotor whirl mode that decides linear
stability); eigenvalues are taken in the upper half plane (Im >= 0, one of each conjugate pair).  On a candidate
grid the eigenvalue compared is the one *nearest* to the reference one (same physical mode); a candidate whose own
rightmost eigenvalue is a different mode ("mode switch") fails as well.

Reference: grids refined by the same ratio in both directions, ``(80, 8), (120, 12), (160, 16), (200, 20)``
(``--quick``: ``(40, 4), (60, 6), (80, 8)``); the finest is the reference.  Its own error is estimated from the
last three: Richardson extrapolation with the observed order where they converge monotonically, and the change
from the next coarser reference grid where they oscillate (no extrapolation is meaningful then).

How the solves are done (all from the project's vector field ``gfbjax.model.balanced_vector_field``):

* one cold solve with :func:`gfbjax.analyses.static.solve_equilibrium` (load homotopy) on a small base grid at
  ``Omega = 0.3``, then a speed sweep on that grid (natural continuation, secant predictor, step halving);
* every other grid is started at each speed from the solution of the nearest already solved grid at the same
  speed, interpolated (pressure field and foil strips, rotor copied); should that Newton fail, the grid falls back
  to a speed sweep from a solved speed, and finally to ``solve_equilibrium``;
* Newton: the one Newton corrector of ``gfbjax.cont``, stepped from the host (:func:`gfbjax.cont.newton_solve_host`,
  so that the steps can use scipy's sparse LU).  This script supplies its linearisation and its damping: one
  jit-compiled function per grid returns ``(J, f)`` (``jax.jacfwd``); steps are solved with a dense LU up to 400
  states and a sparse LU (scipy ``splu``) above; the damping backtracks over the step fractions
  {1, 1/2, ..., 1/64} to the first that keeps the film open and decreases ``|f|_2`` (a full step below the
  tolerance is always taken); converged when a full step has ``|ds|_inf <= 1e-10`` (the tolerance of
  ``solve_equilibrium``).  The recorded ``residual`` of a solve is ``|f|_2`` at the returned state;
* eigenvalues: dense LAPACK for ``n <= 1000``; above that (the reference grids) shift-invert ARPACK
  (``scipy.sparse.linalg.eigs``, ``sigma`` at each of the rightmost eigenvalues of the next coarser solved grid),
  keeping the rightmost of the eigenvalues found.

Usage::

    python benchmarks/grid_convergence.py [--quick] [--tol 0.005] [--speeds 0.05 0.1 0.3 0.6 1.0]

Writes ``benchmarks/results/grid_convergence.json`` and ``grid_convergence.png`` (``--quick``:
``grid_convergence_quick.*``).  BLAS is pinned to one thread unless the environment says otherwise (dense
eigenvalue problems of a few hundred states are faster so on a small shared machine).
"""

from __future__ import annotations

import os

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
import scipy.sparse as sps  # noqa: E402
import scipy.sparse.linalg as spla  # noqa: E402
from scipy.interpolate import RegularGridInterpolator  # noqa: E402

import gfbjax  # noqa: E402  (turns on x64)
from gfbjax import cont  # noqa: E402
from gfbjax.model import balanced_vector_field, layout  # noqa: E402
from gfbjax.analyses.static import solve_equilibrium  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"

FULL = dict(
    candidates_nx=[16, 20, 24, 28, 32, 36, 40, 48, 56, 64, 80],
    candidates_nz=[2, 3, 4, 5, 6, 8, 10],
    reference=[(80, 8), (120, 12), (160, 16), (200, 20)],
    speeds=[0.05, 0.1, 0.3, 0.6, 1.0],
)
QUICK = dict(
    candidates_nx=[16, 24, 32, 40],
    candidates_nz=[2, 3, 4, 6],
    reference=[(40, 4), (60, 6), (80, 8)],
    speeds=[0.1, 0.3, 1.0],
)
BASE_GRID = (16, 2)
COLD_SPEED = 0.3
DENSE_MAX = 1000          # dense eigenvalues up to this many states, shift-invert ARPACK above
N_SHIFTS = 4              # rightmost modes (upper half plane) of the coarser grid used as shifts
XTOL = 1e-10
STEP_FRACTIONS = (1.0, 0.5, 0.25, 0.125, 1 / 16, 1 / 64)


def n_states(nx: int, nz: int) -> int:
    return (nx - 1) * nz + (nx - 1) + 8


def upper(ev: np.ndarray) -> np.ndarray:
    """One eigenvalue of each conjugate pair (Im >= 0), sorted by decreasing real part."""
    ev = np.asarray(ev)
    ev = ev[ev.imag >= -1e-12 * np.maximum(1.0, np.abs(ev))]
    ev = np.where(np.abs(ev.imag) <= 1e-12 * np.maximum(1.0, np.abs(ev)), ev.real + 0j, ev)
    return ev[np.argsort(-ev.real)]


def _jf(s, omega, params):
    f = lambda x: balanced_vector_field(x, omega, params)  # noqa: E731
    return jax.jacfwd(lambda x: (f(x), f(x)), has_aux=True)(s)


def newton_settings(max_iter: int) -> cont.NewtonSettings:
    """Converged at a full step with |ds|_inf <= XTOL, without a further evaluation (the damping keeps |f|
    decreasing, so the residual cannot stall); no divergence test (the damping keeps the iteration monotone)."""
    return cont.NewtonSettings(tol=math.inf, atol_step=XTOL, rtol_step=0.0, max_iter=max_iter,
                               divergence=math.inf, verify_residual=False)


class GridSolver:
    """Equilibria and Jacobian spectra on one grid."""

    def __init__(self, spec, nx: int, nz: int):
        self.nx, self.nz = nx, nz
        # array leaves: no recompilation when the load homotopy of solve_equilibrium scales sigma
        self.params = jax.tree_util.tree_map(jnp.asarray, spec.replace(Nx=nx, Nz=nz).nondim())
        self.lay = layout(self.params)
        self.n = self.lay.n
        assert self.n == n_states(nx, nz), (self.n, n_states(nx, nz))
        self.grid = self.lay.grid
        self.sl = self.lay.slices
        th = np.asarray(self.grid.theta_nodes(float(self.params.theta0)))
        self.cos, self.sin = np.cos(th), np.sin(th)
        self._jf = jax.jit(_jf)
        self._f = jax.jit(balanced_vector_field)
        self.states: dict[float, np.ndarray] = {}
        self.jac: dict[float, np.ndarray] = {}
        self.info: dict[float, dict] = {}
        self.time = 0.0

    # -- residual, Jacobian, Newton ------------------------------------------------------------------------
    def jf(self, s: np.ndarray, omega: float) -> tuple[np.ndarray, np.ndarray]:
        J, r = self._jf(jnp.asarray(s), jnp.asarray(omega), self.params)
        return np.asarray(J), np.asarray(r)

    def h_min(self, s: np.ndarray) -> float:
        q = np.pad(s[self.sl["foil"]], 1)
        xj, yj = s[self.sl["rotor"]][:2]
        return float(np.min(1.0 - xj * self.cos - yj * self.sin + q))

    def f_norm(self, s: np.ndarray, omega: float) -> float:
        return float(np.linalg.norm(np.asarray(self._f(jnp.asarray(s), jnp.asarray(omega), self.params))))

    def _lin_solve(self, J: np.ndarray, r: np.ndarray) -> np.ndarray:
        try:
            if self.n <= 400:
                return np.linalg.solve(J, r)
            return spla.splu(sps.csc_matrix(J)).solve(r)
        except (RuntimeError, np.linalg.LinAlgError) as e:  # a singular Jacobian ends the solve
            raise cont.LinearSolveError(str(e)) from e

    def newton(self, s0: np.ndarray, omega: float, max_iter: int = 25):
        """Damped Newton from s0 (the corrector of ``gfbjax.cont`` with this grid's linearisation and damping, see
        the module docstring); returns (state, J at the state, iterations, |f|_2 at the state) or None on failure."""
        s0 = np.asarray(s0, dtype=float)
        if self.h_min(s0) <= 0.0:  # a closed film: no finite residual to start from
            return None

        def linearise(s):
            J, r = self.jf(np.asarray(s), omega)
            return float(np.max(np.abs(r))), -self._lin_solve(J, r), float(np.linalg.norm(r))

        def damping(s, ds, nr):
            """The first step fraction that keeps the film open and decreases |f|_2 (0: none does).  Returned as
            a NumPy scalar: the corrector negates the comparison ``t > 0`` (``~`` on a Python bool is -2)."""
            s, ds = np.asarray(s), np.asarray(ds)
            small = float(np.max(np.abs(ds))) <= XTOL
            for t in STEP_FRACTIONS:
                s1 = s + t * ds
                if self.h_min(s1) <= 0.0:
                    continue
                n1 = self.f_norm(s1, omega)
                if math.isfinite(n1) and (n1 < nr * (1.0 - 1e-4 * t) or (t == 1.0 and small)):
                    return np.float64(t)
            return np.float64(0.0)

        sol = cont.newton_solve_host(linearise, s0, newton_settings(max_iter), damping=damping)
        if not bool(sol.converged):
            return None
        s = np.asarray(sol.x)
        J, r = self.jf(s, omega)
        return s, J, int(sol.iterations), float(np.linalg.norm(r))

    def accept(self, omega: float, sol, how: str) -> None:
        s, J, it, res = sol
        self.states[omega] = s
        self.jac[omega] = J
        self.info[omega] = {"how": how, "newton_iterations": it, "residual": res, "h_min": self.h_min(s)}

    # -- starts ----------------------------------------------------------------------------------------------
    def cold(self, omega: float) -> bool:
        r = solve_equilibrium(self.params, omega)
        if not r.converged:
            print(f"    solve_equilibrium({self.nx}x{self.nz}, Omega={omega}): {r.outcome}: {r.message}")
            return False
        sol = self.newton(np.asarray(r.state), omega)
        if sol is None:
            return False
        self.accept(omega, sol, f"solve_equilibrium ({r.message}, {r.iterations} Newton iterations)")
        return True

    def sweep(self, targets: list[float], start: float, max_step: float = 0.1, min_step: float = 1e-3) -> None:
        """Natural continuation in speed from the solved speed ``start`` through ``targets``."""
        for direction in (+1, -1):
            goals = sorted([w for w in targets if (w - start) * direction > 0], key=lambda w: abs(w - start))
            om, s, om_prev, s_prev = start, self.states[start], None, None
            for goal in goals:
                while abs(goal - om) > 1e-12:
                    step = min(max_step, abs(goal - om))
                    ok = False
                    while step >= min_step:
                        om1 = om + direction * step
                        if abs(om1 - goal) < 1e-9 or (goal - om1) * direction < 0:
                            om1 = goal
                        guess = s if s_prev is None else s + (s - s_prev) * (om1 - om) / (om - om_prev)
                        if self.h_min(guess) <= 0.0:
                            guess = s
                        sol = self.newton(guess, om1)
                        if sol is not None:
                            ok = True
                            break
                        step *= 0.5
                    if not ok:
                        print(f"    speed sweep on {self.nx}x{self.nz} stalls at Omega = {om:.4g} towards {goal}")
                        break
                    om_prev, s_prev, om, s = om, s, om1, sol[0]
                    if abs(om1 - goal) < 1e-12 and goal not in self.states:
                        self.accept(goal, sol, f"speed sweep from Omega = {start}")
                if abs(goal - om) > 1e-12:
                    break

    # -- grid transfer ---------------------------------------------------------------------------------------
    def fields(self, s: np.ndarray):
        """Full pressure field on (u = theta-fraction, z) nodes and the foil on u nodes."""
        P = np.asarray(self.grid.full_field(jnp.asarray(s[self.sl["pressures"]]).reshape(self.nx - 1, self.nz)))
        u = np.arange(self.nx + 1) / self.nx
        z = np.arange(self.nz + 1) / (2 * self.nz)
        q = np.pad(s[self.sl["foil"]], 1)
        return u, z, P, q, s[self.sl["rotor"]]

    def interpolate_from(self, src: "GridSolver", s_src: np.ndarray) -> np.ndarray:
        u, z, P, q, rot = src.fields(s_src)
        uu = np.arange(1, self.nx) / self.nx
        zz = np.arange(1, self.nz + 1) / (2 * self.nz)
        method = "pchip" if min(len(u), len(z)) >= 4 else "linear"
        Pi = RegularGridInterpolator((u, z), P, method=method)(np.stack(np.meshgrid(uu, zz, indexing="ij"), -1))
        qi = np.interp(uu, u, q)
        return np.concatenate([Pi.reshape(-1), qi, rot])

    # -- eigenvalues -----------------------------------------------------------------------------------------
    def spectrum(self, omega: float, shifts: np.ndarray | None = None) -> dict:
        J = self.jac[omega]
        if self.n <= DENSE_MAX:
            ev = upper(np.linalg.eigvals(J))
            return {"method": "dense", "rightmost": ev[:8]}
        Jc = sps.csc_matrix(J).astype(complex)
        found = []
        for sig in shifts:
            vals = spla.eigs(Jc, k=4, sigma=complex(sig), which="LM", return_eigenvectors=False, tol=1e-12)
            found.extend(vals)
        found = upper(np.array(found))
        # drop duplicates found from neighbouring shifts
        uniq: list[complex] = []
        for v in found:
            if all(abs(v - w) > 1e-8 * max(1.0, abs(v)) for w in uniq):
                uniq.append(v)
        return {"method": f"shift-invert ARPACK at {len(shifts)} shifts", "rightmost": np.array(uniq)[:8]}


# -- driver ------------------------------------------------------------------------------------------------------

def log_distance(a: GridSolver, nx: int, nz: int) -> float:
    return abs(math.log(a.nx / nx)) + abs(math.log(a.nz / nz))


def solve_grid(spec, nx: int, nz: int, speeds: list[float], solved: list[GridSolver], shifts_from=None):
    """Solve one grid at all speeds, warm-started from the nearest solved grid; returns the GridSolver."""
    t0 = time.perf_counter()
    g = GridSolver(spec, nx, nz)
    donors = sorted(solved, key=lambda d: log_distance(d, nx, nz))
    for om in speeds:
        for d in donors:
            if om in d.states:
                sol = g.newton(g.interpolate_from(d, d.states[om]), om)
                if sol is not None:
                    g.accept(om, sol, f"interpolated from {d.nx}x{d.nz}")
                    break
    missing = [om for om in speeds if om not in g.states]
    if missing and g.states:
        start = min(g.states, key=lambda w: min(abs(w - m) for m in missing))
        g.sweep(missing, start)
    for om in [om for om in speeds if om not in g.states]:
        if g.cold(om):
            g.sweep([m for m in speeds if m not in g.states], om)
    g.spectra = {}
    for om in speeds:
        if om not in g.states:
            continue
        shifts = None
        if g.n > DENSE_MAX:
            src = shifts_from if shifts_from is not None else donors[0]
            shifts = src.spectra[om]["rightmost"][:N_SHIFTS]
        g.spectra[om] = g.spectrum(om, shifts)
        g.jac[om] = None  # free memory
    g.time = time.perf_counter() - t0
    return g


def result_of(g: GridSolver, om: float) -> dict:
    s = g.states[om]
    xj, yj = (float(v) for v in s[g.sl["rotor"]][:2])
    ev = g.spectra[om]["rightmost"]
    return {"x_j": xj, "y_j": yj, "lambda": complex(ev[0]), "rightmost": ev}


def richardson(phis: list[float], hs: list[float]) -> dict:
    """Observed order, extrapolated limit and error estimate of the finest of three grids (h1 > h2 > h3).

    Monotone convergence with an order in [0.3, 6]: Richardson extrapolation with the observed order, error
    ``|phi3 - limit|``.  Monotone without such an order: formal order 2.  Oscillatory (the differences change
    sign): no extrapolation; the limit is taken as phi3 and the error estimate is ``|phi3 - phi2|``.
    """
    (p1, p2, p3), (h1, h2, h3) = phis, hs
    d12, d23 = p1 - p2, p2 - p3
    if d12 * d23 < 0.0:
        return {"order": None, "note": "oscillatory: no extrapolation, error estimate |fine - previous|",
                "limit": p3, "error": abs(d23)}
    order, note = 2.0, "formal order 2"
    if d23 != 0.0 and d12 != 0.0:
        ratio = d12 / d23

        def g(p):
            return (h1**p - h2**p) / (h2**p - h3**p) - ratio

        lo, hi = 0.3, 6.0
        if g(lo) * g(hi) < 0.0:
            for _ in range(200):
                mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if g(lo) * g(mid) <= 0.0 else (mid, hi)
            order, note = 0.5 * (lo + hi), "observed order"
        else:
            note = "monotone, no order in [0.3, 6]: formal order 2"
    limit = p3 + (p3 - p2) / ((h2 / h3) ** order - 1.0)
    return {"order": order, "note": note, "limit": limit, "error": abs(p3 - limit)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="small candidate set and reference (a minute or two)")
    ap.add_argument("--tol", type=float, default=0.005, help="relative tolerance (default 0.005 = 0.5%%)")
    ap.add_argument("--speeds", type=float, nargs="+", default=None, help="dimensionless speeds Omega_bar")
    ap.add_argument("--out", type=Path, default=None, help="output JSON (PNG beside it)")
    args = ap.parse_args(argv)
    cfg = QUICK if args.quick else FULL
    speeds = sorted(args.speeds or cfg["speeds"])
    out = args.out or RESULTS / ("grid_convergence_quick.json" if args.quick else "grid_convergence.json")
    spec = gfbjax.reference_system()
    t_start = time.perf_counter()
    print(f"grid convergence of the reference system (w = 0), speeds {speeds}, tol {100 * args.tol:g}%")
    print(f"jax {jax.__version__} on {jax.devices()[0].platform}, {os.cpu_count()} cores, "
          f"BLAS threads {os.environ.get('OPENBLAS_NUM_THREADS')}")

    # 1. base grid: cold start and speed sweep
    t0 = time.perf_counter()
    base = GridSolver(spec, *BASE_GRID)
    if not base.cold(COLD_SPEED):
        print("cold start failed on the base grid", file=sys.stderr)
        return 1
    base.sweep(speeds, COLD_SPEED)
    base.spectra = {om: base.spectrum(om) for om in base.states}
    base.time = time.perf_counter() - t0
    print(f"base grid {BASE_GRID[0]}x{BASE_GRID[1]}: cold start at Omega = {COLD_SPEED} and speed sweep, "
          f"{base.time:.1f} s; solved at {sorted(base.states)}")
    solved = [base]

    # 2. reference grids, coarse to fine (each warm-started from the previous one)
    refs = []
    for nx, nz in cfg["reference"]:
        g = solve_grid(spec, nx, nz, speeds, solved, shifts_from=refs[-1] if refs else None)
        refs.append(g)
        solved.append(g)
        how = {om: g.info[om]["how"] for om in g.states}
        print(f"reference {nx}x{nz} (n = {g.n}): {g.time:.1f} s; " + "; ".join(
            f"{om}: {h}, {g.info[om]['newton_iterations']} it" for om, h in how.items()), flush=True)
    fine = refs[-1]
    ok_speeds = [om for om in speeds if all(om in r.states for r in refs)]
    dropped = sorted(set(speeds) - set(ok_speeds))
    if dropped:
        print(f"WARNING: speeds {dropped} not solved on every reference grid: left out")
    speeds = ok_speeds

    # reference values and their own convergence (Richardson over the last three reference grids)
    ref_vals = {om: result_of(fine, om) for om in speeds}
    rich = refs[-3:]
    hs = [1.0 / r.nx for r in rich]
    fine_check = {}
    for om in speeds:
        rv = ref_vals[om]
        lam_f = rv["lambda"]
        vals = []
        for r in refs:
            rr = result_of(r, om)
            ev = rr["rightmost"]
            lam = complex(ev[np.argmin(np.abs(ev - lam_f))])
            vals.append({"x_j": rr["x_j"], "y_j": rr["y_j"], "re": lam.real, "im": lam.imag,
                         "rightmost": complex(ev[0])})
        ecc = math.hypot(rv["x_j"], rv["y_j"])
        ext = {k: richardson([v[k] for v in vals[-3:]], hs) for k in ("x_j", "y_j", "re", "im")}
        lam_ext = complex(ext["re"]["limit"], ext["im"]["limit"])
        fine_check[om] = {
            "grids": [f"{r.nx}x{r.nz}" for r in refs],
            "x_j": [v["x_j"] for v in vals], "y_j": [v["y_j"] for v in vals],
            "lambda_matched": [[v["re"], v["im"]] for v in vals],
            "rightmost_is_matched": [abs(complex(v["re"], v["im"]) - v["rightmost"]) < 1e-12 for v in vals],
            "richardson_grids": [f"{r.nx}x{r.nz}" for r in rich],
            "richardson": ext,
            "extrapolated": {"x_j": ext["x_j"]["limit"], "y_j": ext["y_j"]["limit"],
                             "lambda": [lam_ext.real, lam_ext.imag]},
            "fine_error_estimate": {
                "position": max(ext["x_j"]["error"], ext["y_j"]["error"]) / ecc,
                "eigenvalue": math.hypot(ext["re"]["error"], ext["im"]["error"]) / abs(lam_f),
            },
            "fine_vs_next_coarser": {
                "position": max(abs(vals[-1]["x_j"] - vals[-2]["x_j"]), abs(vals[-1]["y_j"] - vals[-2]["y_j"])) / ecc,
                "eigenvalue": abs(complex(vals[-1]["re"], vals[-1]["im"]) - complex(vals[-2]["re"], vals[-2]["im"]))
                / abs(lam_f),
            },
        }
    print(f"\nreference grid {fine.nx}x{fine.nz} (n = {fine.n}); its own error estimate from "
          + ", ".join(f"{r.nx}x{r.nz}" for r in rich) + " (Richardson; 'osc' = oscillatory, |fine - previous|):")
    print(f"{'Omega':>6} {'x_j':>10} {'y_j':>10} {'lambda_crit':>24} {'pos err':>9} {'eig err':>9} "
          f"{'d(prev) pos':>11} {'d(prev) eig':>11}  orders x, y, Re, Im")
    for om in speeds:
        rv, fc = ref_vals[om], fine_check[om]
        lam = rv["lambda"]
        orders = ", ".join("osc" if fc["richardson"][k]["order"] is None else f"{fc['richardson'][k]['order']:.2f}"
                           for k in ("x_j", "y_j", "re", "im"))
        print(f"{om:6.3f} {rv['x_j']:10.6f} {rv['y_j']:10.6f} {lam.real:+11.6f}{lam.imag:+11.6f}j "
              f"{100 * fc['fine_error_estimate']['position']:8.4f}% "
              f"{100 * fc['fine_error_estimate']['eigenvalue']:8.4f}% "
              f"{100 * fc['fine_vs_next_coarser']['position']:10.4f}% "
              f"{100 * fc['fine_vs_next_coarser']['eigenvalue']:10.4f}%  {orders}")
    print("reference rightmost eigenvalues (Im >= 0): " + "; ".join(
        f"{om}: " + ", ".join(f"{e.real:+.4f}{e.imag:+.4f}j" for e in ref_vals[om]["rightmost"][:4]) for om in speeds))

    # 3. candidates
    cands = [(nx, nz) for nx in cfg["candidates_nx"] for nz in cfg["candidates_nz"] if nx >= 16]
    cands.sort(key=lambda c: (c[0], c[1]))
    rows = []
    hdr = (f"\n{'grid':>7} {'n':>5}  " + " ".join(f"{'Om=' + format(om, 'g'):>15}" for om in speeds)
           + f" {'max pos':>8} {'max eig':>8}  pass  {'time':>6}")
    print(hdr)
    print(f"{'':>7} {'':>5}  " + " ".join(f"{'pos% / eig%':>15}" for _ in speeds))
    for nx, nz in cands:
        existing = next((r for r in solved if (r.nx, r.nz) == (nx, nz)), None)
        g = existing or solve_grid(spec, nx, nz, speeds, solved)
        if existing is None:
            solved.append(g)
        per = {}
        for om in speeds:
            if om not in g.states:
                per[om] = None
                continue
            rv = ref_vals[om]
            rr = result_of(g, om)
            ecc = math.hypot(rv["x_j"], rv["y_j"])
            ev = rr["rightmost"]
            lam_ref = rv["lambda"]
            lam = complex(ev[np.argmin(np.abs(ev - lam_ref))])
            ext = fine_check[om]["extrapolated"]
            lam_ext = complex(*ext["lambda"])
            per[om] = {
                "x_j": rr["x_j"], "y_j": rr["y_j"], "lambda_matched": [lam.real, lam.imag],
                "lambda_rightmost": [rr["lambda"].real, rr["lambda"].imag],
                "mode_switch": abs(lam - rr["lambda"]) > 1e-12,
                "pos_err": max(abs(rr["x_j"] - rv["x_j"]), abs(rr["y_j"] - rv["y_j"])) / ecc,
                "eig_err": abs(lam - lam_ref) / abs(lam_ref),
                "re_err": abs(lam.real - lam_ref.real) / abs(lam_ref),
                "im_err": abs(lam.imag - lam_ref.imag) / abs(lam_ref),
                "re_err_rel_re": abs(lam.real - lam_ref.real) / abs(lam_ref.real),
                "pos_err_vs_extrapolated": max(abs(rr["x_j"] - ext["x_j"]), abs(rr["y_j"] - ext["y_j"])) / ecc,
                "eig_err_vs_extrapolated": abs(lam - lam_ext) / abs(lam_ext),
                "solve": g.info[om],
            }
        solved_all = all(per[om] is not None for om in speeds)
        mp = max((p["pos_err"] for p in per.values() if p), default=float("nan"))
        me = max((p["eig_err"] for p in per.values() if p), default=float("nan"))
        switch = any(p["mode_switch"] for p in per.values() if p)
        passed = solved_all and mp <= args.tol and me <= args.tol and not switch
        rows.append({"Nx": nx, "Nz": nz, "n": g.n, "per_speed": {str(om): p for om, p in per.items()},
                     "max_pos_err": mp, "max_eig_err": me, "mode_switch": switch, "all_solved": solved_all,
                     "pass": passed, "wall_s": g.time})
        cells = " ".join(f"{100 * p['pos_err']:6.3f}/{100 * p['eig_err']:6.3f}{'*' if p['mode_switch'] else ' '}"
                         if p else f"{'failed':>15}" for p in per.values())
        print(f"{nx:>3}x{nz:<3} {g.n:>5}  {cells} {100 * mp:7.3f}% {100 * me:7.3f}%  "
              f"{'PASS' if passed else 'fail'}  {g.time:5.1f}s", flush=True)

    for r in rows:  # does every candidate at least as fine in both directions pass as well?
        finer = [q for q in rows if q["Nx"] >= r["Nx"] and q["Nz"] >= r["Nz"]]
        r["all_finer_pass"] = all(q["pass"] for q in finer)
    passing = [r for r in rows if r["pass"]]
    chosen = min(passing, key=lambda r: (r["n"], r["Nx"])) if passing else None
    robust = [r for r in rows if r["pass"] and r["all_finer_pass"]]
    chosen_robust = min(robust, key=lambda r: (r["n"], r["Nx"])) if robust else None
    total = time.perf_counter() - t_start
    print("(* = the candidate's own rightmost eigenvalue is another mode than the reference's critical one)")
    if chosen:
        print(f"\nchosen default grid: Nx = {chosen['Nx']}, Nz = {chosen['Nz']} (n = {chosen['n']} states; "
              f"autonomous form {chosen['n'] + 2}); max position error {100 * chosen['max_pos_err']:.3f}%, "
              f"max eigenvalue error {100 * chosen['max_eig_err']:.3f}%")
        if chosen_robust is not chosen and chosen_robust is not None:
            print(f"note: {chosen['Nx']}x{chosen['Nz']} passes, but some finer candidate does not; the smallest "
                  f"grid all of whose refinements pass is {chosen_robust['Nx']}x{chosen_robust['Nz']} "
                  f"(n = {chosen_robust['n']})")
        elif chosen_robust is None:
            print(f"note: {chosen['Nx']}x{chosen['Nz']} passes, but no passing grid has all its refinements pass")
    else:
        print("\nno candidate meets the tolerance")
    d_nx, d_nz = gfbjax.SystemSpec.Nx, gfbjax.SystemSpec.Nz
    cur = next((r for r in rows if (r["Nx"], r["Nz"]) == (d_nx, d_nz)), None)
    if cur:
        print(f"current SystemSpec default {d_nx}x{d_nz} (n = {cur['n']}): max position error "
              f"{100 * cur['max_pos_err']:.3f}%, max eigenvalue error {100 * cur['max_eig_err']:.3f}% "
              f"({'PASS' if cur['pass'] else 'fail'})")
    print(f"total wall time {total:.1f} s")

    def cplx(v):
        return [float(np.real(v)), float(np.imag(v))]

    doc = {
        "what": "grid convergence of the static equilibrium and critical eigenvalue, reference system, w = 0",
        "quick": args.quick, "tol": args.tol, "speeds": speeds, "dropped_speeds": dropped,
        "metrics": {
            "pos_err": "max(|dx_j|, |dy_j|) / |(x_j, y_j)| of the reference grid",
            "eig_err": "|lambda - lambda_ref| / |lambda_ref|, lambda = candidate eigenvalue nearest to the "
                       "reference critical one (Im >= 0)",
            "pass": "pos_err and eig_err <= tol at every speed and the candidate's rightmost eigenvalue is the "
                    "matched mode",
        },
        "base_grid": {"grid": list(BASE_GRID), "cold_speed": COLD_SPEED, "wall_s": base.time,
                      "solves": {str(k): v for k, v in base.info.items()}},
        "reference": {
            "grids": [[r.nx, r.nz, r.n] for r in refs],
            "wall_s": [r.time for r in refs],
            "eigen_method": {f"{r.nx}x{r.nz}": r.spectra[speeds[0]]["method"] for r in refs if speeds},
            "solves": {f"{r.nx}x{r.nz}": {str(k): v for k, v in r.info.items()} for r in refs},
            "values": {str(om): {"x_j": v["x_j"], "y_j": v["y_j"], "lambda_crit": cplx(v["lambda"]),
                                 "rightmost": [cplx(e) for e in v["rightmost"]]} for om, v in ref_vals.items()},
            "self_convergence": {str(k): v for k, v in fine_check.items()},
        },
        "candidates": rows,
        "chosen": None if chosen is None else {k: chosen[k] for k in ("Nx", "Nz", "n", "max_pos_err", "max_eig_err",
                                                                        "all_finer_pass")},
        "chosen_robust": None if chosen_robust is None else {
            k: chosen_robust[k] for k in ("Nx", "Nz", "n", "max_pos_err", "max_eig_err")},
        "total_wall_s": total,
        "machine": {"platform": platform.platform(), "cores": os.cpu_count(), "jax": jax.__version__,
                    "python": platform.python_version()},
    }
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(doc, indent=1, default=lambda o: bool(o) if isinstance(o, np.bool_) else float(o)))
    print(f"wrote {out}")
    try:
        plot(rows, chosen, chosen_robust, args.tol, fine, out.with_suffix(".png"))
        print(f"wrote {out.with_suffix('.png')}")
    except Exception as exc:  # noqa: BLE001 - a missing matplotlib must not lose the JSON
        print(f"no plot: {exc}")
    return 0


def plot(rows, chosen, chosen_robust, tol, fine, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    nzs = sorted({r["Nz"] for r in rows})
    cmap = plt.get_cmap("viridis")
    for ax, key, title in ((axes[0], "max_pos_err", "static journal position"),
                           (axes[1], "max_eig_err", "critical eigenvalue")):
        for i, nz in enumerate(nzs):
            rr = sorted([r for r in rows if r["Nz"] == nz], key=lambda r: r["n"])
            ax.loglog([r["n"] for r in rr], [max(r[key], 1e-7) for r in rr], "o-", ms=4,
                      color=cmap(i / max(1, len(nzs) - 1)), label=f"Nz = {nz}")
        sw = [r for r in rows if r["mode_switch"]]
        if sw:
            ax.loglog([r["n"] for r in sw], [max(r[key], 1e-7) for r in sw], "rx", ms=8, label="mode switch")
        ax.axhline(tol, color="k", ls="--", lw=1, label=f"tol {100 * tol:g}%")
        if chosen:
            ax.loglog([chosen["n"]], [max(chosen[key], 1e-7)], "*", color="C3", ms=16, mfc="none",
                      label=f"chosen {chosen['Nx']}x{chosen['Nz']}")
        if chosen_robust and chosen_robust is not chosen:
            ax.loglog([chosen_robust["n"]], [max(chosen_robust[key], 1e-7)], "s", color="C1", ms=12, mfc="none",
                      label=f"all refinements pass: {chosen_robust['Nx']}x{chosen_robust['Nz']}")
        ax.set_xlabel("states n")
        ax.set_title(f"{title}: max over speeds")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel(f"relative error vs {fine.nx}x{fine.nz}")
    axes[1].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
