r"""Continuation of equilibria  f(x, lam) = 0  with Hopf and fold detection: the equilibrium
:class:`~._driver.Curve`.

Points are :math:`y = (x, \lambda)`.  The corrector is the one Newton corrector (:mod:`._newton`, compiled) on the
bordered system :math:`f(x,\lambda) = 0,\ \langle y - y_k, v\rangle - \Delta s = 0` with the dense Jacobian
:math:`[f_x\ f_\lambda;\ v^T]` (n is at most a few hundred); the same LU gives the unit tangent
:math:`[f_x\ f_\lambda;\ v^T]\tau = e_{n+1}`, oriented by the continuation row.

Eigenvalues of :math:`f_x` are computed at every point.  Test functions:

* fold (limit point): the lam-component of the tangent changes sign;
* branch point (BP): :math:`\operatorname{sign}\det A\ \sigma_{min}(A)` with :math:`A = [f_x\ f_\lambda;\
  \tau^T]`, regular along the branch and at folds, singular where two branches cross; a fold in the same step
  (a side branch turning at the branch point it leaves) is reported as the BP it is.  On such a side branch the
  localisation can land on the crossing branch, so the BP may come out bracketed rather than located;
* Andronov-Hopf: :math:`\psi_H`, the sign of :math:`\prod_{i<j} (\mu_i + \mu_j)/(|\mu_i| + |\mu_j|)` over all
  eigenvalue pairs (the bialternate product of :math:`f_x`) times its two smallest factors
  (:func:`._events.signed_min`): continuous, and of changing sign whenever any pair crosses the imaginary axis,
  whatever else is already unstable.  It also vanishes at a neutral saddle (real pair :math:`\pm\kappa`): a sign
  change is reported as HOPF only when the pair with the smallest factor is complex (its omega is reported).

:func:`hopf_point` returns :math:`(\lambda, x, \omega, v)` with :math:`f_x v = i\omega v`, used by
:func:`._cycles.start_from_hopf`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial
from typing import Any, Callable, NamedTuple, Optional

import jax
import jax.numpy as jnp
import numpy as np

from ._branch import Branch, PointRecord
from ._checks import check_field_at, check_finite, check_index, check_located_state, check_start
from ._checkpoint import as_checkpoint, fingerprint
from ._driver import Curve, continue_curve
from ._events import (ON_BOUNDARY, critical, crossed_members, matched_crossings, name_crossings as _name_crossings,
                      side, sign_changes, signed_min, untracked)
from ._newton import NewtonSettings, solve as newton_solve, with_finite_tangent
from ._problem import EquilibriumProblem
from ._scalars import strong
from ._settings import EquilibriumSettings

__all__ = ["HopfPoint", "continue_equilibria", "hopf_point", "IMAG_TOL"]

IMAG_TOL = 1e-8


@dataclass(frozen=True)
class HopfPoint:
    """Hopf point: f_x(x, lam) v = i omega v, |v| = 1."""

    lam: float
    x: np.ndarray
    omega: float
    v: np.ndarray


class _Row(NamedTuple):
    """The continuation row <y - base, v> - ds = 0."""

    base: jax.Array
    v: jax.Array
    ds: jax.Array


def _linearise(f, args, con: _Row, y):
    def F(y):
        return jnp.concatenate([f(y[:-1], y[-1], args), jnp.atleast_1d(jnp.dot(y - con.base, con.v) - con.ds)])

    r = F(y)
    lu = jax.scipy.linalg.lu_factor(jax.jacfwd(F)(y))
    e = jnp.zeros_like(y).at[-1].set(1.0)
    t = jax.scipy.linalg.lu_solve(lu, e)
    return jnp.max(jnp.abs(r)), jax.scipy.linalg.lu_solve(lu, -r), t / jnp.linalg.norm(t)


@partial(jax.jit, static_argnums=(0, 4))
def _correct(f, args, y0, con, newton: NewtonSettings):
    return newton_solve(lambda y: _linearise(f, args, con, y), y0, newton)


@partial(jax.jit, static_argnums=(0,))
def _augmented_jacobian(f, args, y):
    return jax.jacfwd(lambda yy: f(yy[:-1], yy[-1], args))(y)


@partial(jax.jit, static_argnums=(0,))
def _jacobian(f, args, y):
    return jax.jacfwd(lambda x: f(x, y[-1], args))(y[:-1])


def _eig(problem: EquilibriumProblem, y: np.ndarray):
    ev, V = np.linalg.eig(np.asarray(_jacobian(problem.f, problem.args, jnp.asarray(y))))
    o = np.argsort(-ev.real, kind="stable")
    return ev[o], V[:, o]


def _hopf_factors(ev: np.ndarray):
    """(mu_i + mu_j) / (|mu_i| + |mu_j|) over all pairs i < j of eigenvalues, and the pair indices."""
    ev = np.asarray(ev, complex)
    i, j = np.triu_indices(len(ev), 1)
    return (ev[i] + ev[j]) / (np.abs(ev[i]) + np.abs(ev[j]) + 1e-300), i, j


def _unstable(z: np.ndarray) -> np.ndarray:
    """Eigenvalues on the unstable side (right half plane)."""
    return z.real > 0.0


def _in_units(ev: np.ndarray, *others: np.ndarray) -> tuple[np.ndarray, ...]:
    """``ev`` (and ``others``) in units of the spectral radius of ``ev`` where that is below 1, else as they are.

    The classifications below (real or complex, on the axis or off it) compare with a floor of 1 (``max(1, |z|)``)
    so that rounding in eigenvalues near 0 is not read as an imaginary part.  For a system whose rates are all
    slow (time in units far longer than its own scale: x' = 1e-8 (...)), that floor is far above every
    eigenvalue: a Hopf pair with imaginary part 1e-8 counted as real and was reported as two BPs.  In these units
    the floor is the spectral radius; systems with a radius of 1 or more are unchanged (the factor is exactly 1)."""
    ev = np.asarray(ev, complex)
    rho = float(np.max(np.abs(ev), initial=0.0))
    u = 1.0 / rho if 0.0 < rho < 1.0 else 1.0
    return (ev * u,) + tuple(np.asarray(o, complex) * u for o in others)


def _from_axis(z: np.ndarray) -> np.ndarray:
    """Relative distance of eigenvalues from the imaginary axis (the matching's boundary test)."""
    return np.abs(z.real) / np.maximum(1.0, np.abs(z))


class EquilibriumCurve(Curve):
    kind = "equilibria"
    event_weights = {"FOLD": 1, "BP": 1, "HOPF": 2}  # eigenvalues crossing the imaginary axis at each event

    def __init__(self, problem: EquilibriumProblem, settings: EquilibriumSettings):
        self.problem, self.settings = problem, settings
        self.monitor = problem.monitor
        self.components = problem.components
        self._e_lam = np.zeros(problem.n + 1)
        self._e_lam[-1] = 1.0

    def add(self, a, b):
        return np.asarray(a) + np.asarray(b)

    def scale(self, a, c):
        return np.asarray(a) * c

    def inner(self, a, b):
        return float(np.dot(a, b))

    def lam(self, a):
        return float(a[-1])

    def palc_constraint(self, base, tangent, ds, ref):
        return _Row(jnp.asarray(base), jnp.asarray(tangent), strong(float(ds)))

    def natural_constraint(self, ref, lam):
        base = np.array(ref, float)
        base[-1] = lam
        return _Row(jnp.asarray(base), jnp.asarray(self._e_lam), strong(0.0))

    def correct(self, pred, con):
        sol = _correct(self.problem.f, self.problem.args, jnp.asarray(pred, float), con, self.settings.newton)
        sol = type(sol)(np.asarray(sol.x), np.asarray(sol.aux), sol.code, sol.iterations, sol.residual, sol.step)
        return with_finite_tangent(sol), None

    def null_tangent(self, y):
        J = np.asarray(_augmented_jacobian(self.problem.f, self.problem.args, jnp.asarray(y, float)))
        if not np.all(np.isfinite(J)):
            return None
        v = np.linalg.svd(J)[2][-1]  # right singular vector of the smallest singular value of [f_x f_lam]
        return v * np.sign(v[np.argmax(np.abs(v))])

    def analyse(self, y, lin, tangent):
        J = np.asarray(_augmented_jacobian(self.problem.f, self.problem.args, jnp.asarray(y, float)))
        ev = np.linalg.eigvals(J[:, :-1])
        ev = ev[np.argsort(-ev.real, kind="stable")]
        A = np.vstack([J, np.asarray(tangent, float)[None, :]])
        # the augmented Jacobian [f_x f_lam; tau^T] is regular at folds and singular at branch points: its
        # determinant's sign times its smallest singular value is continuous and changes sign there
        bp = float(np.linalg.slogdet(A)[0] * np.linalg.svd(A, compute_uv=False)[-1])
        an = {"spectrum": ev, "stable": bool(np.all(ev.real < 0)), "trivial_error": float("nan"), "bp": bp}
        if self.monitor is not None:
            an["monitor"] = float(self.monitor.fn(jnp.asarray(y[:-1], float), float(y[-1]), self.problem.args))
        return an

    def tests(self, an, tangent_lam):
        out = {"FOLD": float(tangent_lam), "HOPF": signed_min(_hopf_factors(an["spectrum"])[0]), "BP": an["bp"],
               "UNSTABLE": float(np.sum(np.real(an["spectrum"]) > 0.0)),
               "BOUNDARY": float(np.sum(_from_axis(*_in_units(an["spectrum"])) <= ON_BOUNDARY)),
               # in the units of _in_units (this point's whole spectrum), as crossings and crossing_kinds compare
               "CRITICAL": critical(_in_units(an["spectrum"])[0], lambda z: np.abs(z.real))}
        if self.monitor is not None:
            out["MONITOR"] = an["monitor"] - float(self.monitor.minimum)
        return out

    def crossing_kinds(self, an, count, before=None):
        """``count`` crossings named from the eigenvalues that crossed the imaginary axis since ``before`` (the
        earlier point's ``CRITICAL``; matched), then those nearest it: a complex pair a HOPF (two crossings, with
        its own omega), a real one a BP."""
        ev = np.asarray(an["spectrum"], complex)
        unit = _in_units(ev)[0]
        crossed = [] if before is None else crossed_members(before, unit, _unstable, _from_axis)
        # omega in the problem's time: the named member's index in the spectrum, not its value in other units
        names = _name_crossings(unit, count, lambda z: abs(z.real), "HOPF", lambda z: "BP", crossed)
        return [(k, {"omega": abs(ev[int(np.argmin(np.abs(unit - z)))].imag)} if k == "HOPF" else {})
                for k, z in names]

    def crossings(self, before, after):
        """Eigenvalues that crossed the imaginary axis between two points, by matching (:func:`matched_crossings`);
        ``before``, ``after``: the points' ``CRITICAL`` members, each in the units of its whole spectrum."""
        return matched_crossings(before, after, _unstable, _from_axis)

    def untracked(self, before, after):
        return untracked(before, after, _unstable, _from_axis)

    def events(self, prev, cur, kinds):
        found = sign_changes(prev, cur, kinds)
        if "BP" in found and "FOLD" in found:  # a side branch turns at the branch point it leaves: one event
            found.remove("FOLD")
        return found

    def record(self, y, an, iterations, ds, tangent_lam) -> PointRecord:
        x = np.asarray(y[:-1])
        c = self.components
        return PointRecord(float(y[-1]), float("nan"), float(np.linalg.norm(x)), x[c].copy(), x[c].copy(),
                           an["spectrum"], an["stable"], float("nan"), int(iterations), float(ds), float(tangent_lam),
                           {"x": x.copy()}, an.get("monitor", float("nan")))

    def plotted(self, y):
        x = np.asarray(y[:-1])[self.components]
        return np.concatenate([[float(y[-1])], x, x])

    def state(self, y):
        return {"x": np.asarray(y[:-1]).copy(), "lam": np.asarray(y[-1])}

    def from_state(self, state):
        return np.append(np.asarray(state["x"], float), float(state["lam"]))

    def special(self, kind, y, an, located=True, ends=None):
        if kind == "FOLD" and ends is not None and _at_branch_point(ends):
            return None  # the lam-component of the tangent also vanishes at a branch point: reported as BP
        if kind != "HOPF":
            return {}
        ev = an["spectrum"]
        unit = _in_units(ev)[0]
        f, i, j = _hopf_factors(ev)
        # At a located point the crossing pair has the (near) zero factor.  At an unlocated one (the point after
        # the crossing) a slow pair far from the axis in relative terms can have a smaller normalised factor than
        # the pair that just crossed, so there the pair with the smallest sum |mu_i + mu_j| is taken.
        k = int(np.argmin(np.abs(f) if located else np.abs(ev[i] + ev[j])))
        a, b = unit[i[k]], unit[j[k]]
        if not (abs(a.imag) > IMAG_TOL * max(1.0, abs(a)) and abs(a - np.conj(b)) <= 1e-6 * max(1.0, abs(a))):
            return None  # a real pair +-kappa (neutral saddle): no Hopf bifurcation
        omega = float(abs(ev[i[k]].imag))
        return {"omega": omega, "period": 2 * np.pi / omega}


def _at_branch_point(ends: tuple[dict, dict]) -> bool:
    """Whether a fold located inside a step lies at a branch point: the branch-point test changes sign over the
    step.  Not how small the test is at the fold: it is the smallest singular value of the augmented Jacobian
    (signed), which a slow mode keeps small all along a branch (z' = -1e-7 z beside a fold made every fold a "BP"
    with an absolute threshold of 1e-6), or makes small at the fold alone (z' = -(1e-9 + lam) z, whose rate
    passes 1e-9 there: a threshold relative to the step's ends failed on it)."""
    a, b = (float(e.get("BP", math.nan)) for e in ends)
    return bool(np.isfinite(a) and np.isfinite(b) and side(a) != side(b))


def continue_equilibria(problem: EquilibriumProblem, settings: EquilibriumSettings, x0: Any, lam0: float,
                        *, callback: Optional[Callable[[int, PointRecord], Any]] = None,
                        progress: bool = False, checkpoint: Any = None) -> Branch:
    """Continue equilibria from the guess (x0, lam0), first corrected at fixed lam.  The returned ``Branch``
    stores the eigenvalues of f_x in ``multipliers`` (decreasing real part) and every state in ``states['x']``.
    ``checkpoint``: a folder that every step is appended to and that a later call resumes from (as in
    :func:`gfbjax.cont.continue_cycles`)."""
    if not isinstance(problem, EquilibriumProblem):
        raise ValueError(f"problem must be an EquilibriumProblem, got {type(problem).__name__}")
    if not isinstance(settings, EquilibriumSettings):
        raise ValueError(f"settings must be EquilibriumSettings, got {type(settings).__name__}")
    lam0 = check_start(settings, lam0)
    x0 = check_finite("x0", x0)
    if x0.shape != (problem.n,):
        raise ValueError(f"x0 must have shape (n,) = ({problem.n},), got {x0.shape}")
    out = jax.eval_shape(problem.f, jax.ShapeDtypeStruct((problem.n,), jnp.float64), float(lam0), problem.args)
    if getattr(out, "shape", None) != (problem.n,):
        raise ValueError(f"f(x, lam, args) returned shape {getattr(out, 'shape', type(out).__name__)} for x of "
                         f"shape ({problem.n},); it must return ({problem.n},)")
    check_field_at(problem.f, x0, lam0, problem.args, "x0")
    y0 = np.append(x0, float(lam0))
    ck = as_checkpoint(checkpoint, n=problem.n, problem=fingerprint(problem.f, problem.args),
                       start_data=fingerprint(y0))
    return continue_curve(EquilibriumCurve(problem, settings), settings, y0, callback=callback, progress=progress,
                          desc="equilibria", checkpoint=ck)


def hopf_point(problem: EquilibriumProblem, branch: Branch, which: int = 0) -> HopfPoint:
    """Data of the ``which``-th Hopf point of an equilibrium branch: (lam, x, omega, v) with f_x v = i omega v,
    omega > 0, |v| = 1 and the phase of v chosen so that its largest component is real.  A negative ``which``
    counts from the end, as in Python.

    ``ValueError`` before any work when ``branch`` is not a branch of equilibria, has no HOPF point, ``which`` is
    not an int in [-k, k - 1] for its k HOPF points, the point was not located or has no stored state, or
    ``problem`` is not an :class:`EquilibriumProblem` of the branch's state count."""
    if not isinstance(problem, EquilibriumProblem):
        raise ValueError(f"problem must be an EquilibriumProblem, got {type(problem).__name__}")
    if not isinstance(branch, Branch):
        raise ValueError(f"branch must be a Branch, got {type(branch).__name__}")
    if branch.kind != "equilibria":  # Hopf points are events of equilibria; cycles have PD/NS/LPC/BPC instead
        raise ValueError(f"branch must be a branch of equilibria, got a branch of kind {branch.kind!r}")
    hs = branch.special_of("HOPF")
    if not hs:
        raise ValueError("branch has no HOPF special point")
    h = hs[check_index("which", which, len(hs), "HOPF point")]
    st = check_located_state(branch, h, "refine the model or the steps")
    x = np.asarray(st["x"], float)
    if x.shape != (problem.n,):
        raise ValueError(f"problem.n = {problem.n}, but the branch's equilibria have {x.size} states: pass the "
                         "problem the branch was computed with")
    y = np.append(x, float(st["lam"]))
    ev, V = _eig(problem, y)
    # complex in units of the spectral radius, as the detection classified it (a slow system's Hopf pair has an
    # imaginary part far below IMAG_TOL in its own time units)
    cand = np.where(_in_units(ev)[0].imag > IMAG_TOL)[0]
    if cand.size == 0:  # the branch's Hopf point is not one of this problem (another args or field)
        raise ValueError(f"f_x has no complex eigenvalue at the HOPF point near lam = {h.lam:.6g}: pass the problem "
                         "(f and args) the branch was computed with")
    k = cand[np.argmin(np.abs(ev[cand].real))]
    v = V[:, k]
    v = v * np.exp(-1j * np.angle(v[np.argmax(np.abs(v))]))
    return HopfPoint(float(y[-1]), y[:-1].copy(), float(ev[k].imag), v / np.linalg.norm(v))
