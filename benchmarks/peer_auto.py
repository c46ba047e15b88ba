"""Peer comparison with AUTO-07p: the same problem solved by AUTO-07p and by gfbjax side by side in one run.

Problem: the 1-D Brusselator on x in [0, 1] with Dirichlet ends u = A, v = B/A,

    u_t = D_u / L^2 u_xx + A - (B + 1) u + u^2 v,     v_t = D_v / L^2 v_xx + B u - u^2 v,

discretised by central differences on Nx interior points (spacing h = 1/(Nx+1), n = 2 Nx states, layout
u_1, v_1, u_2, v_2, ...), continuation parameter L (the domain length).  Parameters A = 2, B = 5.45, D_u = 0.008,
D_v = 0.004: the set of AUTO-07p's ``brc`` demo (which discretises the same PDE by Chebyshev collocation instead).
The homogeneous state u = A, v = B/A is an equilibrium for every L; it loses stability at a Hopf point of the
first spatial mode, L_H = sqrt((D_u + D_v) k_1 / (B - 1 - A^2)), k_1 = (2 - 2 cos(pi h)) / h^2 (printed as
"analytic" below; tests/cont/test_cont_brusselator.py checks gfbjax against it).

Steps, in both tools (AUTO-07p through benchmarks/_auto07p.py: an equations file written for this script, with
the exact Jacobian and d/dL (JAC=1, as gfbjax differentiates exactly; ``--auto-jac 0`` lets AUTO difference
instead), compiled against the installed AUTO library and run in a temporary folder):

1. equilibria from L = 0.1 to L = 0.7 (one Hopf point in that range for every Nx), steps 0.01 ... 0.05, Hopf
   point located (AUTO: IPS=1, ISP=2, EPSL=EPSU=1e-10, EPSS=1e-8; gfbjax: ``continue_equilibria`` with its
   defaults newton_tol=1e-11, locate_tol=1e-10).  Timed.
2. the cycle branch from that Hopf point: NTST = N = 20 intervals, NCOL = m = 4 Gauss points, a FIXED uniform mesh
   (AUTO: IAD=0; gfbjax: ``CycleSettings(adapt=0)``), Floquet multipliers and bifurcation detection at every
   point (AUTO: ISP=2, ILP=1; gfbjax: always, detect LPC/PD/NS/BPC with localisation), a fixed number of points
   (``--points``, default 60; AUTO's NMX counts the Hopf start, so NMX = points + 1), DS = 0.01, DSMAX = 0.2 in
   both (their arclength norms differ: AUTO leaves the period out, gfbjax counts it, and their step controls
   differ, so the L range covered differs and is reported).  ``--L-end L`` ends both branches at that L
   instead (AUTO: UZSTOP; gfbjax: lam_max; ``--points`` then caps the points), so that both cover the same
   segment and its special points.  Newton: AUTO's recommended EPSL = EPSU = 1e-7, EPSS = 1e-5 (``--auto-eps``;
   with 1e-9 AUTO's Newton-chord iteration does not converge at the symmetry-breaking branch points of this
   problem and they go unlabelled), ITNW = 8, NWTN = 3; gfbjax its defaults newton_tol = newton_step_tol = 1e-9
   (a step |dx| <= tol (1 + max|x|), the same form as AUTO's EPSU), newton_max_iter = 8.  gfbjax runs with
   each linear solver: ``cont.DenseCondensation()`` (all multipliers, PeriodicQR) and ``cont.SparseSweep()``
   (``CycleProblem(jac_sparsity=...)`` with the exact pattern of the discretisation: u_i couples to u_{i+-1},
   v_i to v_{i+-1}, and u_i, v_i to each other; the default block Krylov multipliers, 12 leading, and the
   Newton-Picard preconditioning of its GMRES solves) for n >= ``--sparse-min-n``.
   Timed; seconds per point = branch wall time / points computed.

Compilation (gfbjax): the cycle branch runs twice in the same process; the first run compiles every kernel the
branch needs (those of the localisations and of their error estimates on 2N intervals too, which a short warm-up
would not reach), and the second is timed.  "compile" below is the first run's time less the second's (before
session 12 the first run had 3 points, and kernels that only the timed run needed compiled inside it: about 2 of
10.8 s at n = 20, dense).  The persistent compilation cache (gfbjax's default) can make the first run faster
where an earlier process compiled the same programs.  Equilibria: a first run of 3 points.  AUTO is compiled
Fortran: its build (gfortran, once per run of this script) is reported apart, and AUTO runs single-threaded
(OMP_NUM_THREADS=1), as gfbjax does on this machine.

Matched points: after both timed runs, ``--matched`` (default 4) values of L evenly inside the range both
branches cover are chosen; AUTO is run again with UZR at those L (labelled user points: AUTO prints L to 11
digits, the period to 11 and multipliers to 6 significant digits), and gfbjax corrects a cycle at exactly the L
AUTO reports (``cont.correct_cycle`` at fixed lam from the branch's stored orbits, interpolated between the two
points around that L, then ``cont.analyse`` with all multipliers of the dense solver).  Compared: the period and
the three leading non-trivial multipliers (largest modulus, the one closest to +1 removed), with each tool's
distance of the trivial multiplier from +1.  The collocation equations are the same in both tools, but a
discrete orbit is invariant under time shifts only up to the discretisation error, and each tool fixes the phase
against its own reference orbit: where the mesh resolves the orbit, the two agree to the Newton tolerance; where
it does not (large |mu_triv - 1|), they differ at that level.  Special points: what
each tool labels (AUTO: BP/LP/PD/TR/HB/MX rows of fort.7, and the NOTE lines of fort.9; gfbjax:
``branch.special`` with type, lam and whether it was located).

Without AUTO-07p (no library objects in $AUTO_DIR/lib or /usr/lib/auto-07p/lib, or no gfortran) the AUTO part is
skipped with one printed message and gfbjax still runs (its matched points then at L of its own branch).

Usage:
    python benchmarks/peer_auto.py                  # n = 4, 20, 50, 100, 200 (long: AUTO and dense grow ~ n^3)
    python benchmarks/peer_auto.py --n 4 20         # chosen sizes n = 2 Nx (even)
    python benchmarks/peer_auto.py --quick          # n = 4, 20 with 20 points; writes peer_auto_quick.json
    python benchmarks/peer_auto.py --n 20 --L-end 2 --points 400   # both branches over the same L range
    options: --points 60 --L-end L --matched 4 --solvers dense sparse --sparse-min-n 20 --auto-eps 1e-7 --out FILE
Writes benchmarks/results/peer_auto.json (``--quick``: peer_auto_quick.json) and prints markdown tables.
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
from typing import Any

import gfbjax  # noqa: F401  (process defaults: x64, XLA flags, single-threaded BLAS) before any JAX work
import jax
import jax.numpy as jnp
import numpy as np
import scipy

from gfbjax import cont

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _auto07p as auto  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"

A, B, DU, DV = 2.0, 5.45, 0.008, 0.004
L0, EQ_END = 0.1, 0.7
N_MESH, M_COLL = 20, 4
DS, DSMAX = 0.01, 0.2
SPARSE_KW: dict = {}  # SparseSweep settings (defaults)


# ---------------------------------------------------------------- the problem, both tools
def brusselator(x, L, p):
    """d/dt of x = (u_1, v_1, ..., u_Nx, v_Nx); p = (A, B, D_u, D_v); Nx from the length of x."""
    a, b, du, dv = p[0], p[1], p[2], p[3]
    nx = x.shape[0] // 2
    h = 1.0 / (nx + 1)
    u, v = x[0::2], x[1::2]
    ub, vb = jnp.atleast_1d(a), jnp.atleast_1d(b / a)
    ue, ve = jnp.concatenate([ub, u, ub]), jnp.concatenate([vb, v, vb])
    cu, cv = du / (L * h) ** 2, dv / (L * h) ** 2
    fu = cu * (ue[:-2] - 2.0 * u + ue[2:]) + a - (b + 1.0) * u + u * u * v
    fv = cv * (ve[:-2] - 2.0 * v + ve[2:]) + b * u - u * u * v
    return jnp.stack([fu, fv], axis=1).ravel()


PARAMS = jnp.array([A, B, DU, DV])


def pattern(nx: int) -> np.ndarray:
    """Exact sparsity of d f / d x: u_i ~ u_{i-1}, u_i, u_{i+1}, v_i;  v_i ~ v_{i-1}, v_i, v_{i+1}, u_i."""
    n = 2 * nx
    P = np.zeros((n, n), bool)
    for i in range(nx):
        for j in (i - 1, i, i + 1):
            if 0 <= j < nx:
                P[2 * i, 2 * j] = P[2 * i + 1, 2 * j + 1] = True
        P[2 * i, 2 * i + 1] = P[2 * i + 1, 2 * i] = True
    return P


def analytic_hopf(nx: int) -> dict[str, float]:
    """First Hopf point of the homogeneous state (mode j = 1 of the discrete Dirichlet Laplacian)."""
    h = 1.0 / (nx + 1)
    k = (2.0 - 2.0 * np.cos(np.pi * h)) / h ** 2
    L = np.sqrt((DU + DV) * k / (B - 1.0 - A * A))
    du, dv = DU * k / L ** 2, DV * k / L ** 2
    det = (B - 1.0 - du) * (-A * A - dv) + B * A * A
    return {"L": float(L), "omega": float(np.sqrt(det))}


def fortran_source() -> str:
    """AUTO-07p equations file of the same discretisation (PAR(1..5) = A, B, D_u, D_v, L; NDIM = 2 Nx)."""
    d = auto.fortran_double
    return f"""! 1-D Brusselator, Dirichlet ends, central differences on NX = NDIM/2 interior points of [0, 1].
! U(2i-1) = u_i, U(2i) = v_i.  PAR: 1 A, 2 B, 3 D_u, 4 D_v, 5 L (diffusion scales with 1/L^2).
SUBROUTINE FUNC(NDIM, U, ICP, PAR, IJAC, F, DFDU, DFDP)
  IMPLICIT NONE
  INTEGER, INTENT(IN) :: NDIM, ICP(*), IJAC
  DOUBLE PRECISION, INTENT(IN) :: U(NDIM), PAR(*)
  DOUBLE PRECISION, INTENT(OUT) :: F(NDIM)
  DOUBLE PRECISION, INTENT(INOUT) :: DFDU(NDIM, NDIM), DFDP(NDIM, *)
  INTEGER :: i, nx, ru, rv
  DOUBLE PRECISION :: a, b, h, cu, cv, ui, vi, ul, vl, ur, vr
  nx = NDIM / 2
  a = PAR(1)
  b = PAR(2)
  h = 1.0D0 / DBLE(nx + 1)
  cu = PAR(3) / (PAR(5) * h)**2
  cv = PAR(4) / (PAR(5) * h)**2
  IF (IJAC > 0) DFDU = 0.0D0
  IF (IJAC > 1) DFDP(:, 1:5) = 0.0D0
  DO i = 1, nx
    ru = 2*i - 1
    rv = 2*i
    ui = U(ru)
    vi = U(rv)
    ul = a
    vl = b / a
    ur = a
    vr = b / a
    IF (i > 1) THEN
      ul = U(ru - 2)
      vl = U(rv - 2)
    END IF
    IF (i < nx) THEN
      ur = U(ru + 2)
      vr = U(rv + 2)
    END IF
    F(ru) = cu * (ul - 2.0D0 * ui + ur) + a - (b + 1.0D0) * ui + ui * ui * vi
    F(rv) = cv * (vl - 2.0D0 * vi + vr) + b * ui - ui * ui * vi
    IF (IJAC > 0) THEN  ! exact Jacobian (AUTO constant JAC = 1)
      DFDU(ru, ru) = -2.0D0 * cu - (b + 1.0D0) + 2.0D0 * ui * vi
      DFDU(ru, rv) = ui * ui
      DFDU(rv, ru) = b - 2.0D0 * ui * vi
      DFDU(rv, rv) = -2.0D0 * cv - ui * ui
      IF (i > 1) THEN
        DFDU(ru, ru - 2) = cu
        DFDU(rv, rv - 2) = cv
      END IF
      IF (i < nx) THEN
        DFDU(ru, ru + 2) = cu
        DFDU(rv, rv + 2) = cv
      END IF
    END IF
    IF (IJAC > 1) THEN  ! d/dL of the diffusion terms
      DFDP(ru, 5) = -2.0D0 / PAR(5) * cu * (ul - 2.0D0 * ui + ur)
      DFDP(rv, 5) = -2.0D0 / PAR(5) * cv * (vl - 2.0D0 * vi + vr)
    END IF
  END DO
END SUBROUTINE FUNC

SUBROUTINE STPNT(NDIM, U, PAR, T)
  IMPLICIT NONE
  INTEGER, INTENT(IN) :: NDIM
  DOUBLE PRECISION, INTENT(INOUT) :: U(NDIM), PAR(*)
  DOUBLE PRECISION, INTENT(IN) :: T
  INTEGER :: i
  PAR(1) = {d(A)}
  PAR(2) = {d(B)}
  PAR(3) = {d(DU)}
  PAR(4) = {d(DV)}
  PAR(5) = {d(L0)}
  DO i = 1, NDIM / 2
    U(2*i - 1) = PAR(1)
    U(2*i) = PAR(2) / PAR(1)
  END DO
END SUBROUTINE STPNT

SUBROUTINE BCND
END SUBROUTINE BCND

SUBROUTINE ICND
END SUBROUTINE ICND

SUBROUTINE FOPT
END SUBROUTINE FOPT

SUBROUTINE PVLS
END SUBROUTINE PVLS
"""


def auto_equilibrium_constants(n: int, jac: int = 1) -> dict[str, Any]:
    return {"NDIM": n, "IPS": 1, "IRS": 0, "ILP": 1, "ICP": [5], "NTST": N_MESH, "NCOL": M_COLL, "IAD": 0,
            "ISP": 2, "ISW": 1, "IPLT": 0, "NBC": 0, "NINT": 0, "NMX": 1000, "NPR": 0, "MXBF": 0, "IID": 2,
            "ITMX": 8, "ITNW": 8, "NWTN": 3, "JAC": jac, "EPSL": 1e-10, "EPSU": 1e-10, "EPSS": 1e-8, "DS": 0.01,
            "DSMIN": 1e-6, "DSMAX": 0.05, "IADS": 1, "NPAR": 11, "UZSTOP": {5: EQ_END}}


def auto_cycle_constants(n: int, points: int, eps: float, L_end: float | None = None, jac: int = 1
                         ) -> dict[str, Any]:
    stop = {} if L_end is None else {"UZSTOP": {5: L_end}}
    return {**stop, "NDIM": n, "IPS": 2, "IRS": "HB1", "ILP": 1, "ICP": [5, 11], "NTST": N_MESH, "NCOL": M_COLL,
            "IAD": 0, "ISP": 2, "ISW": 1, "IPLT": 0, "NBC": 0, "NINT": 0, "NMX": points + 1, "NPR": 0, "MXBF": 0,
            "IID": 2, "ITMX": 8, "ITNW": 8, "NWTN": 3, "JAC": jac, "EPSL": eps, "EPSU": eps, "EPSS": 100 * eps,
            "DS": DS, "DSMIN": 1e-6, "DSMAX": DSMAX, "IADS": 1, "NPAR": 11}


def cycle_settings(points: int, solver: str, L_end: float | None = None) -> cont.CycleSettings:
    lin = cont.DenseCondensation() if solver == "dense" else cont.SparseSweep(**SPARSE_KW)
    return cont.CycleSettings(m=M_COLL, N=N_MESH, adapt=0, ds=DS, ds_max=DSMAX, ds_min=1e-6, max_points=points,
                              lam_max=np.inf if L_end is None else L_end, linear_solver=lin, save_states=True)


# ---------------------------------------------------------------- helpers
def leading(mu: np.ndarray, k: int = 3) -> np.ndarray:
    """The k non-trivial multipliers of largest modulus (the one closest to +1 removed)."""
    nt = cont.nontrivial(np.asarray(mu, complex), 1)
    return nt[np.argsort(-np.abs(nt), kind="stable")][:k]


def cfmt(z: complex) -> str:
    z = complex(z)
    return f"{z.real:.6f}" if abs(z.imag) < 5e-7 else f"{z.real:.5f}{z.imag:+.5f}i"


def cjson(zs) -> list[list[float]]:
    return [[float(complex(z).real), float(complex(z).imag)] for z in zs]


def first_crossing(lam: np.ndarray, L: float) -> int | None:
    """Index i >= 1 with L between lam[i-1] and lam[i] (first such), or None."""
    for i in range(1, len(lam)):
        if (lam[i - 1] - L) * (lam[i] - L) <= 0.0:
            return i
    return None


def gfb_correct_at(prob: cont.CycleProblem, branch: cont.Branch, L: float, settings: cont.CycleSettings):
    """A cycle at exactly lam = L, corrected from the branch's orbits around L; (period, multipliers) or None."""
    i = first_crossing(branch.lam, L)
    if i is None or branch.states is None:
        return None
    st = branch.states
    l0, l1 = float(branch.lam[i - 1]), float(branch.lam[i])
    w = 0.0 if l1 == l0 else (L - l0) / (l1 - l0)
    mesh = np.asarray(st["mesh"])
    mesh = mesh[i] if mesh.ndim == 2 else mesh
    mix = lambda key: (1.0 - w) * np.asarray(st[key][i - 1]) + w * np.asarray(st[key][i])  # noqa: E731
    guess = cont.Orbit(jnp.asarray(mesh), jnp.asarray(mix("xm")), jnp.asarray(mix("xi")), jnp.asarray(mix("T")),
                       jnp.asarray(float(L)))
    sol, lin = cont.correct_cycle(prob, guess, settings=settings)
    if lin is None:
        return None
    an = cont.analyse(prob, lin)
    return float(sol.x.T), np.asarray(an["spectrum"])


def machine_block(load0) -> dict[str, Any]:
    try:
        fc = subprocess.run([os.environ.get("FC", "gfortran"), "--version"], capture_output=True,
                            text=True).stdout.splitlines()[0]
    except (OSError, IndexError):
        fc = None
    return {"platform": platform.platform(), "cpus": os.cpu_count(), "python": platform.python_version(),
            "jax": jax.__version__, "numpy": np.__version__, "scipy": scipy.__version__,
            "gfbjax": gfbjax.__version__, "gfortran": fc, "load_avg_start": list(load0),
            "load_avg_end": list(os.getloadavg()), "OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS"),
            "auto_OMP_NUM_THREADS": 1}


# ---------------------------------------------------------------- one size
def run_auto(exe: Path, n: int, points: int, eps: float, L_end: float | None, jac: int) -> dict[str, Any]:
    eq = auto.run(exe, auto_equilibrium_constants(n, jac))
    hb = [r for r in eq.rows if r["type"] == "HB"]
    out: dict[str, Any] = {"equilibria": {"wall_s": eq.wall_s, "points": len(eq.rows),
                                          "labels": [{"type": r["type"], "L": r["PAR(5)"]} for r in eq.labelled()],
                                          "returncode": eq.returncode}}
    if not hb:
        out["error"] = f"no Hopf point found by AUTO in L in [{L0}, {EQ_END}]"
        return out
    out["hopf_L"] = hb[0]["PAR(5)"]
    cy = auto.run(exe, auto_cycle_constants(n, points, eps, L_end, jac), start=eq.s)
    rows = [r for r in cy.rows if r["pt"] > 1]  # PT 1 is the Hopf point itself
    start = [r for r in cy.rows if r["pt"] == 1]
    notes = [ln.strip() for ln in cy.d.splitlines() if "NOTE:" in ln]
    out["cycles"] = {
        "wall_s": cy.wall_s, "points": len(rows), "per_point_s": cy.wall_s / max(len(rows), 1),
        "L_range": [out["hopf_L"], max(r["PAR(5)"] for r in rows)] if rows else None,
        "L_end": rows[-1]["PAR(5)"] if rows else None,
        "newton_iterations": auto.newton_iterations(cy.d),
        "hopf_period": start[0].get("PERIOD") if start else None,
        "labels": [{"type": r["type"], "L": r["PAR(5)"], "pt": r["pt"], "period": r.get("PERIOD")}
                   for r in cy.labelled() if r["pt"] > 1],
        "notes": notes, "returncode": cy.returncode,
        "unstable_points": int(sum(not r["stable"] for r in rows)),
        "lam": [r["PAR(5)"] for r in rows], "_start": eq.s,
    }
    return out


def run_gfbjax(nx: int, points: int, solvers: list[str], L_end: float | None) -> dict[str, Any]:
    n = 2 * nx
    x0 = np.tile([A, B / A], nx)
    ep = cont.EquilibriumProblem(brusselator, n, PARAMS)
    eqs = dict(ds=0.01, ds_max=0.05, lam_max=EQ_END, max_points=1000)
    t0 = time.perf_counter()
    cont.continue_equilibria(ep, cont.EquilibriumSettings(**{**eqs, "max_points": 3}), x0, L0)
    t_first = time.perf_counter() - t0
    t0 = time.perf_counter()
    eb = cont.continue_equilibria(ep, cont.EquilibriumSettings(**eqs), x0, L0)
    t_eq = time.perf_counter() - t0
    out: dict[str, Any] = {"equilibria": {
        "wall_s": t_eq, "points": len(eb), "first_run_3_points_s": t_first,
        "compile_s": max(t_first - 3 * t_eq / max(len(eb), 1), 0.0), "outcome": str(eb.outcome),
        "specials": [{"type": s.type, "lam": float(s.lam), "located": bool(s.located)} for s in eb.special]}}
    if not eb.special_of("HOPF"):
        out["error"] = f"no Hopf point found by gfbjax in L in [{L0}, {EQ_END}] ({eb.outcome}: {eb.message})"
        return out
    hopf = cont.hopf_point(ep, eb)
    out["hopf_L"], out["hopf_omega"] = hopf.lam, hopf.omega
    out["cycles"] = {}
    for solver in solvers:
        prob = cont.CycleProblem(brusselator, n, PARAMS, jac_sparsity=pattern(nx))
        st = cycle_settings(points, solver, L_end)
        t0 = time.perf_counter()
        cont.continue_cycles(prob, st, cont.start_from_hopf(hopf, st))  # compiles every kernel the branch needs
        t_first = time.perf_counter() - t0
        t0 = time.perf_counter()
        br = cont.continue_cycles(prob, st, cont.start_from_hopf(hopf, st))
        wall = time.perf_counter() - t0
        P = max(len(br), 1)
        out["cycles"][solver] = {
            "wall_s": wall, "points": len(br), "per_point_s": wall / P, "first_run_s": t_first,
            "compile_s": max(t_first - wall, 0.0), "outcome": str(br.outcome), "message": br.message,
            "L_range": [float(np.min(br.lam)), float(np.max(br.lam))] if len(br) else None,
            "L_end": float(br.lam[-1]) if len(br) else None,
            "newton_iterations": int(np.sum(br.newton_iterations)),
            "max_trivial_error": float(np.nanmax(br.trivial_error)) if len(br) else None,
            "unstable_points": int(np.sum(~br.stable)),
            "specials": [{"type": s.type, "lam": float(s.lam), "located": bool(s.located),
                          "period": float(s.period)} for s in br.special],
            "_branch": br, "_problem": prob, "_settings": st}
    return out


def matched_points(res_auto, res_gfb, exe, n, points, eps, jac, count) -> list[dict[str, Any]]:
    """Period and leading multipliers at ``count`` common values of L (see the module docstring)."""
    solver = next(iter(res_gfb["cycles"]))
    g = res_gfb["cycles"][solver]
    br, prob = g["_branch"], g["_problem"]
    dense = cycle_settings(points, "dense")
    if len(br) < 2:
        return []
    top = float(np.max(br.lam))
    have_auto = res_auto is not None and "cycles" in res_auto and res_auto["cycles"]["lam"]
    if have_auto:
        top = min(top, max(res_auto["cycles"]["lam"]))
    lo = float(res_gfb["hopf_L"])
    targets = [round(lo + (top - lo) * (k + 1) / (count + 1), 4) for k in range(count)]
    targets = sorted({t for t in targets if lo < t < top})
    auto_pts: dict[float, dict[str, Any]] = {}
    if have_auto and targets:
        # the user points shorten steps: allow more of them, and stop at the last user point
        c = {**auto_cycle_constants(n, 4 * points + 10, eps, jac=jac), "UZR": {5: targets},
             "STOP": [f"UZ{len(targets)}"]}
        uz = auto.run(exe, c, start=res_auto["cycles"]["_start"])
        mults = auto.parse_multipliers(uz.d)
        for r in uz.rows:
            if r["type"] == "UZ":
                t = min(targets, key=lambda x: abs(x - r["PAR(5)"]))
                if t not in auto_pts:
                    auto_pts[t] = {"L": r["PAR(5)"], "period": r["PERIOD"], "mu": mults.get(r["pt"]),
                                   "stable": r["stable"]}
    out = []
    for t in targets:
        a = auto_pts.get(t)
        L = a["L"] if a else t
        gc = gfb_correct_at(prob, br, L, dense)
        rec: dict[str, Any] = {"L_target": t, "L": L}
        if gc is not None:
            T, mu = gc
            rec["gfbjax"] = {"period": T, "leading": cjson(leading(mu)), "trivial_error": cont.trivial_error(mu),
                             "stable": bool(np.all(np.abs(cont.nontrivial(mu, 1)) < 1.0))}
        if a is not None and a["mu"] is not None:
            la = leading(a["mu"])
            rec["auto"] = {"period": a["period"], "leading": cjson(la), "stable": bool(a["stable"]),
                           "trivial_error": cont.trivial_error(a["mu"])}
            if gc is not None:
                nt = cont.nontrivial(gc[1], 1)
                rec["period_diff"] = abs(gc[0] - a["period"])
                rec["max_mu_diff"] = float(max(np.min(np.abs(nt - z)) for z in la))
        out.append(rec)
    return out


def study(nx: int, a, inst, exe) -> dict[str, Any]:
    n = 2 * nx
    solvers = [s for s in a.solvers if (s == "dense" and n <= a.dense_max_n) or (s == "sparse" and n >= a.sparse_min_n)]
    print(f"\n== n = {n} (Nx = {nx}): solvers {solvers}", flush=True)
    rec: dict[str, Any] = {"n": n, "Nx": nx, "analytic_hopf": analytic_hopf(nx)}
    res_auto = None
    if inst is not None:
        t0 = time.perf_counter()
        res_auto = run_auto(exe, n, a.points, a.auto_eps, a.L_end, a.auto_jac)
        print(f"   AUTO done ({time.perf_counter() - t0:.1f} s)", flush=True)
    t0 = time.perf_counter()
    res_gfb = run_gfbjax(nx, a.points, solvers, a.L_end)
    print(f"   gfbjax done ({time.perf_counter() - t0:.1f} s)", flush=True)
    rec["matched"] = [] if "cycles" not in res_gfb else matched_points(
        res_auto, res_gfb, exe, n, a.points, a.auto_eps, a.auto_jac, a.matched)
    if res_auto is not None and "cycles" in res_auto:
        res_auto["cycles"] = {k: v for k, v in res_auto["cycles"].items() if not k.startswith("_")}
    for v in res_gfb.get("cycles", {}).values():
        for k in [k for k in v if k.startswith("_")]:
            del v[k]
    rec["auto"], rec["gfbjax"] = res_auto, res_gfb
    return rec


# ---------------------------------------------------------------- report
def print_tables(recs: list[dict[str, Any]]) -> None:
    def f(x, spec=".4g"):
        return "-" if x is None else format(x, spec)

    print("\n### Hopf point of the homogeneous state (first mode) and equilibrium continuation "
          f"L = {L0} -> {EQ_END}\n")
    print("| n | analytic L_H | AUTO L_H | gfbjax L_H | gfbjax - AUTO | gfbjax - analytic | AUTO eq [s] | "
          "gfbjax eq [s] (compile) |")
    print("|---|---|---|---|---|---|---|---|")
    for r in recs:
        au, gf = r["auto"] or {}, r["gfbjax"]
        la, lg = au.get("hopf_L"), gf.get("hopf_L")
        d = None if la is None or lg is None else lg - la
        dan = None if lg is None else lg - r["analytic_hopf"]["L"]
        ae = au.get("equilibria", {}).get("wall_s")
        ge = gf["equilibria"]
        print(f"| {r['n']} | {r['analytic_hopf']['L']:.10f} | {f(la, '.10f')} | {f(lg, '.10f')} | {f(d, '.2e')} | "
              f"{f(dan, '.2e')} | {f(ae, '.4f')} | {ge['wall_s']:.3f} ({ge['compile_s']:.1f}) |")

    print("\n### Cycle branch from the Hopf point (N = 20, m = 4, fixed mesh, multipliers at every point)\n")
    print("| n | tool | points | L reached | Newton its | branch [s] | s/point | time per point / AUTO's | compile [s] |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in recs:
        au = (r["auto"] or {}).get("cycles")
        if au:
            print(f"| {r['n']} | AUTO-07p | {au['points']} | {f(au['L_end'], '.4f')} | {au['newton_iterations']} | "
                  f"{au['wall_s']:.3f} | {au['per_point_s']:.2e} | 1 | - |")
        for name, g in r["gfbjax"].get("cycles", {}).items():
            ratio = None if not au else g["per_point_s"] / au["per_point_s"]
            which = "-" if ratio is None else (f"{ratio:.2g} ({ratio:.1f}x slower)" if ratio >= 1
                                               else f"{ratio:.2g} ({1 / ratio:.1f}x faster)")
            print(f"| {r['n']} | gfbjax {name} | {g['points']} | {f(g['L_end'], '.4f')} | {g['newton_iterations']} | "
                  f"{g['wall_s']:.2f} | {g['per_point_s']:.2e} | {which} | {g['compile_s']:.1f} |")

    print("\n### Matched points: period and leading non-trivial Floquet multipliers at the same L\n")
    print("| n | L | T AUTO | T gfbjax | abs dT | leading mu AUTO | leading mu gfbjax | max abs dmu | "
          "abs(mu_triv - 1) AUTO / gfbjax |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in recs:
        for m in r["matched"]:
            au, gf = m.get("auto"), m.get("gfbjax")
            mus = lambda x: "-" if x is None else ", ".join(cfmt(complex(*z)) for z in x["leading"])  # noqa: E731
            print(f"| {r['n']} | {m['L']:.8f} | {f(au and au['period'], '.8f')} | {f(gf and gf['period'], '.8f')} | "
                  f"{f(m.get('period_diff'), '.1e')} | {mus(au)} | {mus(gf)} | {f(m.get('max_mu_diff'), '.1e')} | "
                  f"{f(au and au['trivial_error'], '.1e')} / {f(gf and gf['trivial_error'], '.1e')} |")

    print("\n### Special points on the cycle branch\n")
    print("(each tool over its own L range, column 'L reached' above: a point beyond the other tool's range is no "
          "disagreement; rerun with --L-end for a common range)\n")
    print("| n | tool | special points (type at L) |")
    print("|---|---|---|")
    for r in recs:
        au = (r["auto"] or {}).get("cycles")
        if au:
            s = ", ".join(f"{x['type']} {x['L']:.5f}" for x in au["labels"] if x["type"] not in ("EP", "UZ")) or "none"
            print(f"| {r['n']} | AUTO-07p | {s}{'; ' + str(len(au['notes'])) + ' NOTE lines' if au['notes'] else ''} |")
        for name, g in r["gfbjax"].get("cycles", {}).items():
            s = ", ".join(f"{x['type']} {x['lam']:.5f}{'' if x['located'] else ' (not located)'}"
                          for x in g["specials"]) or "none"
            print(f"| {r['n']} | gfbjax {name} | {s} (outcome {g['outcome']}) |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, nargs="+", default=[4, 20, 50, 100, 200], help="state counts n = 2 Nx")
    ap.add_argument("--quick", action="store_true", help="n = 4, 20 with 20 points (writes peer_auto_quick.json)")
    ap.add_argument("--points", type=int, default=60, help="cycle points per branch (with --L-end: at most)")
    ap.add_argument("--L-end", type=float, default=None, help="end both cycle branches at this L")
    ap.add_argument("--matched", type=int, default=4, help="number of matched L values")
    ap.add_argument("--solvers", nargs="+", default=["dense", "sparse"], choices=["dense", "sparse"])
    ap.add_argument("--sparse-min-n", type=int, default=20, help="run the sparse solver from this n on")
    ap.add_argument("--dense-max-n", type=int, default=100,
                    help="run the dense solver up to this n (its cost grows as n^3: minutes per branch at n = 200)")
    ap.add_argument("--auto-eps", type=float, default=1e-7, help="AUTO's EPSL = EPSU on cycles (EPSS = 100x)")
    ap.add_argument("--auto-jac", type=int, default=1, choices=[0, 1],
                    help="AUTO's JAC: 1 the exact Jacobian of the equations file, 0 AUTO's finite differences")
    ap.add_argument("--out", type=Path, default=None)
    a = ap.parse_args()
    if a.quick:
        a.n, a.points = [4, 20], 20
    bad = [n for n in a.n if n < 4 or n % 2]
    if bad:
        ap.error(f"n must be even and >= 4 (n = 2 Nx), got {bad}")
    out = a.out or RESULTS / ("peer_auto_quick.json" if a.quick else "peer_auto.json")
    load0 = os.getloadavg()

    inst, why = auto.locate()
    exe = None
    build_s = None
    tmp = tempfile.TemporaryDirectory(prefix="peer_auto_")
    if inst is None:
        print(f"AUTO-07p part skipped: {why}", flush=True)
    else:
        t0 = time.perf_counter()
        exe = inst.build(fortran_source(), Path(tmp.name), "brus")
        build_s = time.perf_counter() - t0
        print(f"{inst.version}: equations file built in {build_s:.2f} s", flush=True)
    try:
        recs = [study(n // 2, a, inst, exe) for n in a.n]
    finally:
        tmp.cleanup()
    print_tables(recs)
    doc = {
        "benchmark": "peer comparison with AUTO-07p: discretised 1-D Brusselator, first Hopf point and cycle branch",
        "problem": {"A": A, "B": B, "D_u": DU, "D_v": DV, "domain": "[0, 1], Dirichlet u = A, v = B/A",
                    "discretisation": "central differences on Nx interior points, h = 1/(Nx+1), diffusion / L^2",
                    "equilibria_L": [L0, EQ_END]},
        "settings": {"N": N_MESH, "m": M_COLL, "mesh": "fixed uniform (AUTO IAD=0, gfbjax adapt=0)",
                     "points": a.points, "L_end": a.L_end, "ds": DS, "ds_max": DSMAX, "auto_eps_cycles": a.auto_eps,
                     "auto_epss_cycles": 100 * a.auto_eps, "auto_jac": a.auto_jac, "auto_eps_equilibria": 1e-10,
                     "gfbjax_newton_tol": cont.CycleSettings().newton_tol, "solvers": a.solvers,
                     "sparse_min_n": a.sparse_min_n, "dense_max_n": a.dense_max_n, "matched": a.matched},
        "auto": {"available": inst is not None, "reason": why or None,
                 "version": None if inst is None else inst.version,
                 "dir": None if inst is None else str(inst.dir), "build_s": build_s},
        "results": recs,
        "machine": machine_block(load0),
        "date": time.strftime("%Y-%m-%d %H:%M"),
        "note": "wall times on a shared 2-core machine; other processes may have run at the same time (load_avg)",
    }
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(doc, indent=1, default=float) + "\n")
    print(f"\nwrote {out}")


if __name__ == "__main__":
    main()
