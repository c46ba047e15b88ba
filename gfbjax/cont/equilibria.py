r"""Continuation of equilibria  f(x, lam) = 0  with Hopf and fold detection.

Pseudo-arclength system for :math:`y = (x, \lambda)`:

.. math::  f(x,\lambda) = 0, \qquad \langle y - y_k, \tau_k\rangle - \Delta s = 0,

solved by Newton with the dense bordered Jacobian
:math:`[f_x\ f_\lambda;\ \tau_k^T]` (n is at most a few hundred).  The tangent
solves :math:`[f_x\ f_\lambda;\ \tau_k^T]\tau = e_{n+1}` and is normalised.

Eigenvalues of :math:`f_x` are computed at every point.  Test functions:

* fold (limit point): the lam-component of the tangent changes sign;
* Andronov-Hopf: :math:`\psi_H = \max \operatorname{Re}\mu` over the
  eigenvalues with non-zero imaginary part changes sign (neutral saddles,
  real pairs :math:`\pm\kappa`, are thereby excluded).

Both are localised by the Illinois regula falsi in arclength
(``events.locate``).  ``hopf_point`` returns :math:`(\lambda, x, \omega, v)`
with :math:`f_x v = i\omega v` used by ``palc.start_from_hopf``.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import Any, Callable, Optional

import jax
import jax.numpy as jnp
import numpy as np

from .branch import Branch, PointRecord
from .events import locate
from .problem import check_step_settings, EquilibriumProblem, check_range

IMAG_TOL = 1e-8


@dataclass(frozen=True)
class EquilibriumSettings:
    ds: float = 0.05
    ds_min: float = 1e-8
    ds_max: float = 0.5
    direction: int = 1
    max_points: int = 200
    lam_min: float = -np.inf
    lam_max: float = np.inf
    newton_tol: float = 1e-11
    newton_max_iter: int = 10
    fast_iter: int = 3
    grow: float = 1.5
    detect: tuple[str, ...] = ("FOLD", "HOPF")
    locate: bool = True
    locate_tol: float = 1e-10

    def __post_init__(self) -> None:
        check_step_settings(self)
        if not self.lam_min < self.lam_max:
            raise ValueError(f"lam_min must be < lam_max, got lam_min={self.lam_min}, lam_max={self.lam_max}")
        check_range("newton_tol", self.newton_tol, 0.0, 1.0, lo_open=True)
        check_range("newton_max_iter", self.newton_max_iter, 1, 1000, integer=True)
        check_range("fast_iter", self.fast_iter, 1, self.newton_max_iter, integer=True)
        check_range("grow", self.grow, 1.0, 10.0)
        bad = [d for d in self.detect if d not in ("FOLD", "HOPF")]
        if bad:
            raise ValueError(f"detect entries must be in ('FOLD', 'HOPF'), got {bad}")
        check_range("locate_tol", self.locate_tol, 0.0, 1.0, lo_open=True)


@dataclass(frozen=True)
class HopfPoint:
    """Hopf point: f_x(x, lam) v = i omega v, |v| = 1."""

    lam: float
    x: np.ndarray
    omega: float
    v: np.ndarray


@partial(jax.jit, static_argnums=(0,))
def _bordered(f, args, y, yk, tau, ds):
    """Residual and Jacobian of the pseudo-arclength system at y = (x, lam)."""
    def F(y):
        return jnp.concatenate([f(y[:-1], y[-1], args), jnp.atleast_1d(jnp.dot(y - yk, tau) - ds)])
    return F(y), jax.jacfwd(F)(y)


def _newton(problem, settings, y, yk, tau, ds):
    """Returns (y, converged, iterations)."""
    for it in range(1, settings.newton_max_iter + 1):
        r, J = _bordered(problem.f, problem.args, y, yk, tau, ds)
        dy = np.linalg.solve(np.asarray(J), -np.asarray(r))
        if not np.all(np.isfinite(dy)):
            return y, False, it
        y = y + dy
        if np.max(np.abs(dy)) <= settings.newton_tol * (1 + np.max(np.abs(y))):
            r, _ = _bordered(problem.f, problem.args, y, yk, tau, ds)
            return y, bool(np.max(np.abs(np.asarray(r))) <= max(1e3 * settings.newton_tol, 1e-9)), it
    return y, False, settings.newton_max_iter


def _tangent(problem, y, tau_prev):
    _, J = _bordered(problem.f, problem.args, y, y, tau_prev, 0.0)
    rhs = np.zeros(len(y))
    rhs[-1] = 1.0
    t = np.linalg.solve(np.asarray(J), rhs)
    return t / np.linalg.norm(t)


def _eig(problem, y):
    _, J = _bordered(problem.f, problem.args, y, y, np.zeros(len(y)), 0.0)
    ev, V = np.linalg.eig(np.asarray(J)[:-1, :-1])
    o = np.argsort(-ev.real, kind="stable")
    return ev[o], V[:, o]


def _tests(ev, tlam):
    c = ev[np.abs(ev.imag) > IMAG_TOL * np.maximum(1, np.abs(ev))]
    return {"FOLD": float(tlam), "HOPF": float(np.max(c.real)) if len(c) else -np.inf}


def _record(problem, y, ev, iters, ds, tlam):
    x = y[:-1]
    c = problem.components
    return PointRecord(float(y[-1]), float("nan"), float(np.linalg.norm(x)), x[c].copy(), x[c].copy(),
                       ev, bool(np.all(ev.real < 0)), float("nan"), iters, ds, tlam, {"x": x.copy()})


def continue_equilibria(problem: EquilibriumProblem, settings: EquilibriumSettings, x0: Any, lam0: float,
                        *, callback: Optional[Callable[[int, PointRecord], Any]] = None) -> Branch:
    """Continue equilibria from the guess (x0, lam0); the guess is first
    corrected at fixed lam.  The returned ``Branch`` stores eigenvalues of
    f_x in ``multipliers`` and every state in ``states['x']``."""
    s = settings
    points: list[PointRecord] = []
    special: list[dict[str, Any]] = []
    sp_states: list[dict[str, np.ndarray]] = []
    reason = "unknown"
    try:
        reason = _loop(problem, s, np.asarray(x0, float), float(lam0), points, special, sp_states, callback)
    except KeyboardInterrupt:
        reason = "interrupted"
    except Exception as e:
        reason = f"error: {e!r}"
    return Branch.from_points("equilibria", problem.components, points, special, sp_states, reason)


def _loop(problem, s, x0, lam0, points, special, sp_states, callback) -> str:
    n = problem.n
    e_lam = np.zeros(n + 1)
    e_lam[-1] = 1.0
    y0 = np.append(x0, lam0)
    y, ok, it = _newton(problem, s, y0, y0, e_lam, 0.0)
    if not ok:
        return "start point did not converge"
    tau = _tangent(problem, y, e_lam) * s.direction
    ev, _ = _eig(problem, y)
    tests = _tests(ev, tau[-1])
    points.append(_record(problem, y, ev, it, 0.0, tau[-1]))
    ds = s.ds
    while len(points) < s.max_points:
        yn, ok, it = _newton(problem, s, y + ds * tau, y, tau, ds)
        if not ok:
            ds *= 0.5
            if ds < s.ds_min:
                return f"step size below ds_min={s.ds_min}"
            continue
        tau_n = _tangent(problem, yn, tau)
        ev_n, _ = _eig(problem, yn)
        tests_n = _tests(ev_n, tau_n[-1])
        for kind in s.detect:
            a, b = tests[kind], tests_n[kind]
            if np.isfinite(a) and np.isfinite(b) and np.sign(a) * np.sign(b) < 0:
                _locate(problem, s, kind, y, tau, ds, a, b, yn, ev_n, points, special, sp_states)
        points.append(_record(problem, yn, ev_n, it, ds, tau_n[-1]))
        if callback is not None and callback(len(points) - 1, points[-1]) is False:
            return "stopped by callback"
        y, tau, tests = yn, tau_n, tests_n
        if not (s.lam_min <= y[-1] <= s.lam_max):
            return f"lam={y[-1]:.6g} left [lam_min, lam_max]"
        if it <= s.fast_iter:
            ds = min(ds * s.grow, s.ds_max)
    return "max_points reached"


def _locate(problem, s, kind, y, tau, ds, a, b, yn, ev_n, points, special, sp_states):
    yy, ev, located = yn, ev_n, False
    if s.locate:
        def g(sv):
            yr, ok, it = _newton(problem, s, y + sv * tau, y, tau, sv)
            if not ok:
                return float("nan"), None
            e, _ = _eig(problem, yr)
            t = _tangent(problem, yr, tau)
            return _tests(e, t[-1])[kind], (yr, e, it, t[-1], sv)

        _, payload, _, located = locate(g, ds, a, b, tol=s.locate_tol)
        if payload is not None:
            yy, ev, it, tl, sv = payload
            points.append(_record(problem, yy, ev, it, sv, tl))
        else:
            located = False
    info: dict[str, Any] = {"type": kind, "index": len(points) - 1 if located else len(points),
                            "lam": float(yy[-1]), "period": float("nan"), "multipliers": ev,
                            "located": bool(located), "angle": None, "state": len(sp_states)}
    if kind == "HOPF":
        c = ev[np.abs(ev.imag) > IMAG_TOL]
        k = np.argmin(np.abs(c.real))
        info["angle"] = float(abs(c[k].imag))  # omega
        info["period"] = 2 * np.pi / info["angle"]
    sp_states.append({"x": yy[:-1].copy(), "lam": np.asarray(yy[-1])})
    special.append(info)


def hopf_point(problem: EquilibriumProblem, branch: Branch, which: int = 0) -> HopfPoint:
    """Data of the ``which``-th located Hopf point of an equilibrium branch:
    (lam, x, omega, v) with f_x v = i omega v, omega > 0, |v| = 1 and the
    phase of v chosen so that its largest component is real."""
    hs = branch.special_of("HOPF")
    if not hs:
        raise ValueError("branch has no HOPF special point")
    sp = hs[which]
    st = branch.special_states[sp["state"]]
    y = np.append(st["x"], float(st["lam"]))
    ev, V = _eig(problem, y)
    cand = np.where(ev.imag > IMAG_TOL)[0]
    k = cand[np.argmin(np.abs(ev[cand].real))]
    v = V[:, k]
    v = v * np.exp(-1j * np.angle(v[np.argmax(np.abs(v))]))
    return HopfPoint(float(y[-1]), y[:-1].copy(), float(ev[k].imag), v / np.linalg.norm(v))
