r"""The one continuation driver: predictor, corrector, step control, event detection and localisation, recording.

It is written once for every kind of branch.  What is continued (periodic orbits, equilibria) is a
:class:`Curve`: it knows its vector space (``add``, ``scale``, ``inner``, ``lam``), its constraints, how to correct a
prediction (returning the tangent there), how to analyse a converged point (multipliers or eigenvalues), its test
functions and how to record a point.  The algorithm (:class:`~._settings.PseudoArclength`,
:class:`~._settings.Natural`) makes the prediction.

One step from a converged point :math:`X_k` with unit tangent :math:`\tau_k`:

1. predict :math:`X^{(0)}` (algorithm) and correct with Newton (:mod:`._newton`);
2. a failed correction halves ds; the branch ends with ``STEP_TOO_SMALL`` below ``ds_min``;
3. analyse the new point, evaluate the test functions, and for each event between the two points localise it:
   the Illinois regula falsi in the arclength ``s`` from the left point, each evaluation a full correction at
   ``X_k + s tau_k``; a located point is inserted in the branch with its test-function residual;
4. record, call the callback; grow ds after a fast correction.

A step that reaches or crosses ``lam_min``/``lam_max`` is replaced by a correction at lam = the bound (from the
secant): the last point lies on the bound, and no point or event beyond it is recorded (``REACHED_END``).

Whatever ends the branch, the points computed so far are returned in a :class:`~._branch.Branch` with its
:class:`~._results.Outcome`.  KeyboardInterrupt (and SIGTERM, where the caller maps it to KeyboardInterrupt) ends
it with ``INTERRUPTED``, a numerical failure of the linear algebra (:class:`~._newton.LinearSolveError`, e.g.
Arnoldi without convergence) with ``LINEAR_SOLVE_FAILED``; any other exception (a bug in the vector field, a
wrong shape) propagates.
"""
from __future__ import annotations

import abc
import math
from typing import Any, Callable, Optional

import numpy as np

from ._branch import Branch, PointRecord
from ._newton import LinearSolveError
from ._results import Outcome, SpecialPoint

__all__ = ["Curve", "continue_curve", "locate"]


class Curve(abc.ABC):
    """What a branch is made of; implemented for cycles (:mod:`._cycles`) and equilibria (:mod:`._equilibria`)."""

    kind: str  # "cycles" | "equilibria"

    # ---- vector space of the points (X = unknowns including lam)
    @abc.abstractmethod
    def add(self, a: Any, b: Any) -> Any: ...

    @abc.abstractmethod
    def scale(self, a: Any, c: float) -> Any: ...

    @abc.abstractmethod
    def inner(self, a: Any, b: Any) -> float: ...

    @abc.abstractmethod
    def lam(self, a: Any) -> float: ...

    @abc.abstractmethod
    def palc_constraint(self, base: Any, tangent: Any, ds: float, ref: Any) -> Any: ...

    @abc.abstractmethod
    def natural_constraint(self, ref: Any, lam: float) -> Any: ...

    # ---- solving and analysing
    @abc.abstractmethod
    def correct(self, pred: Any, con: Any) -> tuple[Any, Any]:
        """(NewtonSolution with ``aux`` = the unit tangent, a linearisation for :meth:`analyse`)."""

    @abc.abstractmethod
    def analyse(self, X: Any, lin: Any, tangent: Any) -> dict[str, Any]:
        """``spectrum`` (multipliers or eigenvalues, sorted), ``stable``, ``trivial_error`` (and whatever the test
        functions need) of a converged point with its unit tangent."""

    @abc.abstractmethod
    def tests(self, analysis: dict[str, Any], tangent_lam: float) -> dict[str, float]: ...

    @abc.abstractmethod
    def events(self, prev: dict[str, float], cur: dict[str, float], detect: tuple[str, ...]) -> list[str]: ...

    @abc.abstractmethod
    def record(self, X: Any, analysis: dict[str, Any], iterations: int, ds: float, tangent_lam: float
               ) -> PointRecord: ...

    @abc.abstractmethod
    def state(self, X: Any) -> dict[str, np.ndarray]: ...

    @abc.abstractmethod
    def special(self, kind: str, X: Any, analysis: dict[str, Any], located: bool = True) -> dict[str, Any] | None:
        """Type-specific fields of a special point (``period``, ``angle``, ``omega``), or None when the sign change
        of the test function is not a bifurcation (e.g. two real multipliers with product 1 for NS); ``located``
        False: X is the first point past the event, not the event itself."""

    def null_tangent(self, X: Any) -> Any:
        """A unit vector spanning the null space of the Jacobian at X (with respect to the unknowns and lam), to
        start where fixing lam is singular (a fold), oriented so that its largest component is positive; None
        when the curve cannot compute it (then such a start fails with START_FAILED)."""
        return None

    def branch(self, points, special, special_states, outcome, message, settings) -> Branch:
        return Branch.from_points(self.kind, self.components, points, special, special_states, outcome, message)

    components: list[int]  # recorded state components (their max/min over a cycle are stored)


def locate(g: Callable[[float], tuple[float, Any]], s_hi: float, g_lo: float, g_hi: float, *,
           tol: float = 1e-9, s_tol: float = 1e-10, max_iter: int = 30) -> tuple[float, Any, float, bool]:
    """Zero of g(s) on (0, s_hi) by the Illinois regula falsi.

    ``g(s)`` returns (value, payload) and may return (nan, None) on failure.  Returns (s, payload, value,
    located): located when |g| <= tol, or when the bracket has shrunk below s_tol * s_hi with |g| below 1e-6 of
    its end values (a continuous root); not located when g jumps across a closed bracket, when g_lo and g_hi do
    not bracket a zero (no evaluation then) or when the iteration budget runs out.
    """
    a, b, ga, gb = 0.0, float(s_hi), float(g_lo), float(g_hi)
    if not (np.sign(ga) * np.sign(gb) <= 0):
        return b, None, gb, False
    side = 0
    best = (b, None, gb)
    for _ in range(max_iter):
        if ga == gb:
            s = 0.5 * (a + b)
        else:
            s = b - gb * (b - a) / (gb - ga)
            if not (min(a, b) < s < max(a, b)):
                s = 0.5 * (a + b)
        gs, payload = g(s)
        if not np.isfinite(gs):
            s = 0.5 * (a + b)
            gs, payload = g(s)
            if not np.isfinite(gs):
                return best[0], best[1], best[2], False
        best = (s, payload, gs)
        if abs(gs) <= tol:
            return s, payload, gs, True
        if abs(b - a) <= s_tol * max(1.0, abs(s_hi)):
            # The bracket closed.  A continuous test function is then tiny next to its values at the ends; one that
            # jumps across the bracket (a critical eigenvalue swapping, a discontinuous model) is not: bracketed,
            # not located.
            return s, payload, gs, abs(gs) <= 1e-6 * max(abs(g_lo), abs(g_hi))
        if np.sign(gs) == np.sign(gb):
            b, gb = s, gs
            if side == -1:
                ga *= 0.5
            side = -1
        else:
            a, ga = s, gs
            if side == +1:
                gb *= 0.5
            side = +1
    return best[0], best[1], best[2], False


class _Run:
    """The mutable record of one continuation (points, special points, their states)."""

    def __init__(self, curve: Curve, settings: Any, callback, bar):
        self.curve, self.s, self.callback, self.bar = curve, settings, callback, bar
        self.points: list[PointRecord] = []
        self.special: list[SpecialPoint] = []
        self.special_states: list[dict[str, np.ndarray]] = []

    def add_point(self, rec: PointRecord) -> bool:
        """Record an accepted point; False when the callback asks to stop."""
        self.points.append(rec)
        if self.bar is not None:
            self.bar.update(1)
        return not (self.callback is not None and self.callback(len(self.points) - 1, rec) is False)

    def tangent_lam(self, tau) -> float:
        return float(self.curve.lam(tau))


def continue_curve(curve: Curve, settings: Any, X0: Any, tau0: Any = None, *,
                   callback: Optional[Callable[[int, PointRecord], Any]] = None, progress: bool = False,
                   desc: str = "branch") -> Branch:
    """Continue ``curve`` from ``X0``.

    ``tau0=None``: ``X0`` is a guess, corrected at fixed lam and recorded; the first tangent points towards
    increasing lam times ``settings.direction``.  Where fixing lam is singular (X0 at a fold) the guess is
    corrected along the null tangent of the Jacobian instead (curves that provide :meth:`Curve.null_tangent`),
    and ``direction`` chooses between the two halves of the branch (+1: along the null tangent oriented with its
    largest component positive).  Otherwise ``X0`` is a bifurcation point (Hopf, PD) and ``tau0``
    the direction of the emanating branch (``X0`` itself is not recorded).  ``callback(index, record)`` is called
    after each accepted point (return ``False`` to stop).
    """
    bar = None
    if progress:
        from tqdm.auto import tqdm
        bar = tqdm(total=settings.max_points, desc=desc)
    run = _Run(curve, settings, callback, bar)
    try:
        outcome, message = _loop(run, X0, tau0)
    except KeyboardInterrupt:
        outcome, message = Outcome.INTERRUPTED, "interrupted; the points computed so far are kept"
    except LinearSolveError as exc:  # e.g. Arnoldi without convergence: a numerical failure, not a bug
        outcome, message = Outcome.LINEAR_SOLVE_FAILED, f"{exc} (after {len(run.points)} points)"
    finally:
        if bar is not None:
            bar.close()
    return curve.branch(run.points, run.special, run.special_states, outcome, message, settings)


def _loop(run: _Run, X0: Any, tau0: Any) -> tuple[Outcome, str]:
    c, s = run.curve, run.s
    algo = s.algorithm
    if tau0 is None:
        sol, lin = c.correct(X0, c.natural_constraint(X0, c.lam(X0)))
        if sol.converged:
            X, tau = sol.x, c.scale(sol.aux, float(s.direction))
        else:  # at a fold (or on a branch vertical in lam) fixing lam is singular: start along the null tangent
            v = c.null_tangent(X0)
            if v is None:
                return Outcome.START_FAILED, f"start point did not converge ({sol.outcome})"
            sol, lin = c.correct(X0, c.palc_constraint(X0, v, 0.0, X0))
            if not sol.converged:
                return Outcome.START_FAILED, f"start point did not converge, not even along its null tangent " \
                                             f"({sol.outcome})"
            X, tau = sol.x, c.scale(sol.aux, float(s.direction))
        an = c.analyse(X, lin, tau)
        tests = c.tests(an, run.tangent_lam(tau))
        if not run.add_point(c.record(X, an, int(sol.iterations), 0.0, run.tangent_lam(tau))):
            return Outcome.STOPPED, "stopped by the callback"
    else:
        X, tau, tests = X0, tau0, None
    X_prev = None
    ds = s.ds
    while len(run.points) < s.max_points:
        pred, con, ds, direction = algo.predict(c, X, X_prev, tau, ds, s.direction, s.dlam_max)
        sol, lin = c.correct(pred, con)
        if not sol.converged:
            ds *= 0.5
            if ds < s.ds_min:
                return Outcome.STEP_TOO_SMALL, (f"step size below ds_min = {s.ds_min:g} at lam = {c.lam(X):.6g} "
                                                f"(last correction: {sol.outcome})")
            continue
        Xn, tau_n = sol.x, sol.aux
        if direction is None:  # natural parameter: orient the corrector's tangent by the stepping direction
            tau_n = c.scale(tau_n, float(s.direction))
        bound = _crossed_bound(s, c.lam(X), c.lam(Xn))
        if bound is not None:  # place the last point on the bound: nothing is recorded or detected beyond it
            placed = _on_bound(c, X, Xn, tau, bound)
            if placed is None:
                return Outcome.REACHED_END, (f"lam = {c.lam(Xn):.6g} left [lam_min, lam_max] = [{s.lam_min:g}, "
                                             f"{s.lam_max:g}]; the point on the bound did not converge")
            sol, lin, tau_n = placed
            Xn = sol.x
        an_n = c.analyse(Xn, lin, tau_n)
        tests_n = c.tests(an_n, run.tangent_lam(tau_n))
        if tests is not None and s.detect:
            for kind in c.events(tests, tests_n, s.detect):
                _event(run, kind, X, direction, ds, tests, tests_n, Xn, an_n)
        if not run.add_point(c.record(Xn, an_n, int(sol.iterations), ds, run.tangent_lam(tau_n))):
            return Outcome.STOPPED, "stopped by the callback"
        X_prev, X, tau, tests = X, Xn, tau_n, tests_n
        if bound is not None:
            return Outcome.REACHED_END, f"lam = {bound:.6g} reached (bounds [lam_min, lam_max] = [{s.lam_min:g}, " \
                                        f"{s.lam_max:g}])"
        if int(sol.iterations) <= s.fast_iter:
            ds = min(ds * s.grow, s.ds_max)
    return Outcome.MAX_POINTS, f"max_points = {s.max_points} reached"


def _crossed_bound(s: Any, lam0: float, lam1: float) -> float | None:
    """The bound of [lam_min, lam_max] that the step lam0 -> lam1 reached or crossed, if any."""
    if lam1 >= s.lam_max > -np.inf and lam0 < s.lam_max:
        return float(s.lam_max)
    if lam1 <= s.lam_min < np.inf and lam0 > s.lam_min:
        return float(s.lam_min)
    if not (s.lam_min <= lam1 <= s.lam_max):  # started outside the bounds
        return float(np.clip(lam1, s.lam_min, s.lam_max))
    return None


def _on_bound(c: Curve, X: Any, Xn: Any, tau: Any, bound: float):
    """Correct at lam = bound from the secant between X and Xn: (solution, linearisation, tangent oriented like
    ``tau``), or None when it does not converge."""
    lam0, lam1 = c.lam(X), c.lam(Xn)
    w = (bound - lam0) / (lam1 - lam0) if lam1 != lam0 else 1.0
    pred = c.add(X, c.scale(c.add(Xn, c.scale(X, -1.0)), w))
    sol, lin = c.correct(pred, c.natural_constraint(pred, bound))
    if not sol.converged:
        return None
    t = sol.aux
    if tau is not None and c.inner(t, tau) < 0:
        t = c.scale(t, -1.0)
    return sol, lin, t


def _event(run: _Run, kind: str, X: Any, tau: Any, ds: float, tests: dict, tests_n: dict, Xn: Any,
           an_n: dict) -> None:
    """Localise ``kind`` between X (left) and Xn and insert the special point (located: as a new row)."""
    c, s = run.curve, run.s
    point, an, located, residual = Xn, an_n, False, math.nan
    if s.locate and tau is not None:
        def g(sv):
            pred = c.add(X, c.scale(tau, sv))
            sol, lin = c.correct(pred, c.palc_constraint(X, tau, sv, pred))
            if not sol.converged:
                return float("nan"), None
            a = c.analyse(sol.x, lin, sol.aux)
            tl = float(c.lam(sol.aux))
            return c.tests(a, tl)[kind], (sol, a, tl)

        sv, payload, val, located = locate(g, ds, tests[kind], tests_n[kind], tol=s.locate_tol)
        if payload is not None:  # located, or bracketed where the test function jumps (residual not small)
            sol, an, tl = payload
            point, residual = sol.x, float(val)
        located = bool(located and payload is not None)
    extra = c.special(kind, point, an, located)
    if extra is None:  # the test function changed sign, but not at a bifurcation (module docstring of the curve)
        return
    if np.isfinite(residual):  # a point of the localisation: inserted as a row of the branch
        run.points.append(c.record(point, an, int(sol.iterations), sv, tl))
    run.special_states.append(c.state(point))
    run.special.append(SpecialPoint(type=kind, lam=float(c.lam(point)),
                                    index=len(run.points) - 1 if np.isfinite(residual) else len(run.points),
                                    spectrum=np.asarray(an["spectrum"]), located=bool(located), residual=residual,
                                    state=len(run.special_states) - 1, **extra))
