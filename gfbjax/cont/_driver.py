r"""The one continuation driver: predictor, corrector, step control, event detection and localisation, recording.

It is written once for every kind of branch.  What is continued (periodic orbits, equilibria) is a
:class:`Curve`: it knows its vector space (``add``, ``scale``, ``inner``, ``lam``), its constraints, how to correct a
prediction (returning the tangent there), how to analyse a converged point (multipliers or eigenvalues), its test
functions and how to record a point.  The algorithm (:class:`~._settings.PseudoArclength`,
:class:`~._settings.Natural`) makes the prediction.

One step from a converged point :math:`X_k` with unit tangent :math:`\tau_k`:

1. predict :math:`X^{(0)}` (algorithm) and correct with Newton (:mod:`._newton`);
2. a failed correction halves ds; the branch ends with ``STEP_TOO_SMALL`` below ``ds_min``;
3. a tangent that turned by more than ``max_angle`` from the last one halves ds and retries (a jump to another
   branch, or a bend the step does not resolve);
4. analyse the new point, evaluate the test functions, and for each event between the two points localise it
   (:mod:`._localise`): the Illinois regula falsi in the arclength ``s`` from the left point, each evaluation a full
   correction at ``X_k + s tau_k``; a located point is inserted in the branch with its test-function residual.  An
   event that cannot be located halves ds and retries the step (up to ``event_refine`` times): a corrector that
   jumped to another branch changes the sign of a test function without a zero between, and so does a test function
   the step does not resolve; a shorter step either removes the spurious event or locates the real one.  The count
   of halvings runs until the event is passed (a step that stops short of it does not restart it).  Branch points
   (BP, BPC) whose localisation failed because the corrections close to them did not converge are not refined: those
   corrections are singular next to a branch point, which says nothing about the step; they are reported as not
   located.  Crossings of the stability boundary that no sign change accounts for (two events in one step cancel in
   a test function) refine the step the same way; those left after the last halving (events closer than the shortest
   step) are reported as not located, named from the eigenvalues nearest the boundary
   (:meth:`Curve.crossing_kinds`);
5. record, call the callback; grow ds after a fast correction, and with ``chord_tol`` bound it by the curvature of
   the recorded curve (:func:`_chord_factor`): points gather where the branch bends.

A step that reaches or crosses ``lam_min``/``lam_max`` is replaced by a correction at lam = the bound (from the
secant): the last point lies on the bound, and no point or event beyond it is recorded (``REACHED_END``).

With a :class:`~._checkpoint.Checkpoint`, every accepted step is appended to a folder, together with the driver's
state after it (point, previous point, tangent, test functions, next ds); a later call with the same folder resumes
from there and gives the same branch as an uninterrupted run.

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
from ._checkpoint import Checkpoint
from ._newton import LinearSolveError
from ._localise import SINGULAR_EVENTS, Found, add_discretisation_error, bracket, localise, step_span
from ._results import Outcome, SpecialPoint

__all__ = ["Curve", "continue_curve"]


class Curve(abc.ABC):
    """What a branch is made of; implemented for cycles (:mod:`._cycles`) and equilibria (:mod:`._equilibria`)."""

    kind: str  # "cycles" | "equilibria"
    #: events -> how many eigenvalues (multipliers) cross into the unstable side at each; with an "UNSTABLE"
    #: count among the test data, a step whose count changes by more than its sign changes explain is refined
    event_weights: dict[str, int] = {}
    monitor: Any = None  # the problem's Monitor (a physical bound); its value is the test "MONITOR" (value - min)

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
    def plotted(self, X: Any) -> np.ndarray:
        """What a plot of the branch shows of X, as :func:`_plotted` reads it from X's record (lam, then the
        recorded components' maxima and minima), without the record's analyses."""

    @abc.abstractmethod
    def state(self, X: Any) -> dict[str, np.ndarray]: ...

    @abc.abstractmethod
    def from_state(self, state: dict[str, np.ndarray]) -> Any:
        """The point (or tangent) whose :meth:`state` is ``state`` (for resuming from a checkpoint)."""

    def adapt(self, X: Any, tau: Any, X_prev: Any, tests: dict | None, count: int) -> tuple[Any, Any, Any, Any]:
        """After the ``count``-th recorded point: the point, tangent, previous point and test functions on a
        better discretisation (cycles: an adapted mesh); unchanged by default."""
        return X, tau, X_prev, tests

    @abc.abstractmethod
    def special(self, kind: str, X: Any, analysis: dict[str, Any], located: bool = True,
                ends: tuple[dict, dict] | None = None) -> dict[str, Any] | None:
        """Type-specific fields of a special point (``period``, ``angle``, ``omega``), or None when the sign change
        of the test function is not a bifurcation (e.g. two real multipliers with product 1 for NS); ``located``
        False: X is the first point past the event, not the event itself.  ``ends``: the test functions at the
        step's two ends, where known (what "small" means for a test value at X: relative to its values there)."""

    def family_ends(self, X: Any, left: Any, right: Any) -> dict[str, Any] | None:
        """Whether a fold located at X between the step's ends ``left`` and ``right`` is no fold but the end of
        the family, where it was born (cycles that shrink to an equilibrium: a Hopf point; period-doubled cycles
        that shrink onto the cycle of half their period: a period doubling); then the end's special point fields
        (``type`` "HOPF" or "PD", ``period``, ``omega`` for a Hopf point), else None (the default: a curve whose
        folds are folds)."""
        return None

    def collapsed(self, X: Any, guess: Any, before: Any = None) -> dict[str, Any] | None:
        """Whether X, a converged correction of ``guess``, is no member of the curve but a degenerate solution of
        its equations (cycles: the constant orbit, which solves them with any period, or a cycle of half the
        period traversed twice); then, as :meth:`family_ends`, the fields of the family's end there, with its
        estimated ``lam`` and ``lam_error`` (``before``: the member before ``guess``, where known), else None (the
        default)."""
        return None

    def passed_end(self, X: Any, Xn: Any) -> dict[str, Any] | None:
        """Whether the step from X to Xn ran through the point where the family was born and on along its mirror
        image (cycles: through zero amplitude at a Hopf point, or through the cycle of half the period at a period
        doubling: :func:`._collocation.passed_through`); then, as :meth:`collapsed`, the end's fields with its
        estimated ``lam`` and ``lam_error``, else None (the default)."""
        return None

    def border_solve(self, X: Any, lin: Any) -> np.ndarray | None:
        """A^{-1} b (flat) for a fixed vector b, A the augmented Jacobian at X of the linearisation ``lin``; None
        when the curve does not provide it or the solve fails.  Used to place branch points across the gap where
        corrections fail (:func:`._localise._across_the_gap`)."""
        return None

    def other_discretisations(self, X: Any, tau: Any) -> list[tuple[Any, Any]]:
        """X and its tangent carried to other discretisations (finer, or as fine but placed differently), on which
        a special point at X is located once more to estimate its discretisation error (``SpecialPoint.lam_error``,
        the largest move); empty when the curve has no discretisation (equilibria: the ODE itself is solved)."""
        return []

    def crossings(self, before: np.ndarray, after: np.ndarray) -> int:
        """How many members of the spectrum crossed the stability boundary between two points whose test data
        hold ``CRITICAL`` = ``before`` and ``after`` (the members nearest the boundary), by matching; 0 by
        default."""
        return 0

    def untracked(self, before: np.ndarray, after: np.ndarray) -> bool:
        """Whether the step between two points whose test data hold ``CRITICAL`` = ``before`` and ``after`` moved
        the spectrum too far to tell by matching whether one member left the stable side while another entered
        (:func:`._events.untracked`); False by default."""
        return False

    def crossing_kinds(self, analysis: dict[str, Any], count: int,
                       before: np.ndarray | None = None) -> list[tuple[str, dict[str, Any]]]:
        """(name, data) for ``count`` crossings of the stability boundary that no test function's sign change
        accounts for (two events closer together than the shortest step), read off the eigenvalues (multipliers)
        in ``analysis`` that crossed since the step's first point (``before``: its ``CRITICAL`` test data), then
        those nearest the boundary; ``data`` is the crossing member's own (``omega``, ``angle``), which
        :meth:`special` would give as the same for every crossing.  Empty by default (then they are not
        reported)."""
        return []

    def null_tangent(self, X: Any) -> Any:
        """A unit vector spanning the null space of the Jacobian at X (with respect to the unknowns and lam), to
        start where fixing lam is singular (a fold), oriented so that its largest component is positive; None
        when the curve cannot compute it (then such a start fails with START_FAILED)."""
        return None

    def branch(self, points, special, special_states, outcome, message, settings) -> Branch:
        return Branch.from_points(self.kind, self.components, points, special, special_states, outcome, message,
                                  monitor_info=None if self.monitor is None else self.monitor.describe())

    components: list[int]  # recorded state components (their max/min over a cycle are stored)


class _Run:
    """The mutable record of one continuation (points, special points, their states)."""

    def __init__(self, curve: Curve, settings: Any, callback, bar, checkpoint: Checkpoint | None = None):
        self.curve, self.s, self.callback, self.bar = curve, settings, callback, bar
        self.checkpoint = checkpoint
        self.points: list[PointRecord] = []
        self.special: list[SpecialPoint] = []
        self.special_states: list[dict[str, np.ndarray]] = []
        self.reported = 0  # rows the callback and the bar have seen

    def add_point(self, rec: PointRecord) -> bool:
        """Record an accepted point and report every row not reported yet (a row inserted at a located special
        point comes before the step's point) to the bar and the callback; False when the callback asks to stop."""
        self.points.append(rec)
        while self.reported < len(self.points):
            i = self.reported
            self.reported += 1
            if self.bar is not None:
                self.bar.update(1)
            if self.callback is not None and self.callback(i, self.points[i]) is False:
                return False
        return True

    def accept(self, rec: PointRecord, X: Any, X_prev: Any, tau: Any, tests: dict | None, ds: float,
               driver: dict | None = None) -> bool:
        """End of an accepted step: record its point, append the step with the state that the next step starts
        from to the checkpoint (before the callback, so that an interrupting callback loses nothing), then call
        the callback; False when it asks to stop."""
        if self.checkpoint is not None:
            c = self.curve
            self.checkpoint.append(self.points + [rec], self.special, self.special_states, c.state(X),
                                   None if X_prev is None else c.state(X_prev), c.state(tau), tests, ds, driver)
        return self.add_point(rec)

    def tangent_lam(self, tau) -> float:
        return float(self.curve.lam(tau))


def continue_curve(curve: Curve, settings: Any, X0: Any, tau0: Any = None, *,
                   callback: Optional[Callable[[int, PointRecord], Any]] = None, progress: bool = False,
                   desc: str = "branch", checkpoint: Checkpoint | None = None) -> Branch:
    """Continue ``curve`` from ``X0``.

    ``tau0=None``: ``X0`` is a guess, corrected at fixed lam and recorded; the first tangent points towards
    increasing lam times ``settings.direction``.  Where fixing lam is singular (X0 at a fold) the guess is
    corrected along the null tangent of the Jacobian instead (curves that provide :meth:`Curve.null_tangent`),
    and ``direction`` chooses between the two halves of the branch (+1: along the null tangent oriented with its
    largest component positive).  Otherwise ``X0`` is a bifurcation point (Hopf, PD) and ``tau0``
    the direction of the emanating branch (``X0`` itself is not recorded).  ``callback(index, record)`` is called
    for each row of the branch as it is recorded, in order, rows inserted at located special points included
    (return ``False`` to stop).

    ``checkpoint``: every accepted step is appended to this folder (:mod:`._checkpoint`).  If it already holds
    steps of the same continuation, the branch resumes after the last one (``X0``/``tau0`` are then not used, and
    ``callback`` first sees the last restored point); if that branch had ended, it is returned as stored.
    :class:`~._checkpoint.CheckpointError` when the folder belongs to another continuation.
    """
    restored = None if checkpoint is None else checkpoint.open(curve.kind, settings)
    if restored is not None and restored.outcome is not None:
        return curve.branch(restored.points, restored.special, restored.special_states, restored.outcome,
                            restored.message, settings)
    bar = None
    if progress:
        from tqdm.auto import tqdm
        bar = tqdm(total=settings.max_points, desc=desc)
    run = _Run(curve, settings, callback, bar, checkpoint)
    outcome, message = Outcome.INTERRUPTED, "interrupted; the points computed so far are kept"
    try:
        outcome, message = _loop(run, X0, tau0, restored)
    except KeyboardInterrupt:
        outcome, message = Outcome.INTERRUPTED, "interrupted; the points computed so far are kept"
    # e.g. Arnoldi without convergence, or LAPACK's SVD or eigenvalue iteration failing on a matrix with NaN:
    # numerical failures, not bugs
    except (LinearSolveError, np.linalg.LinAlgError) as exc:
        outcome, message = Outcome.LINEAR_SOLVE_FAILED, f"{exc} (after {len(run.points)} points)"
    finally:
        if bar is not None:
            bar.close()
        if checkpoint is not None:
            checkpoint.finish(outcome, message)
    return curve.branch(run.points, run.special, run.special_states, outcome, message, settings)


def _resume(run: _Run, restored: Any) -> tuple[Any, Any, Any, Any, float] | None:
    """Put the restored rows into ``run`` (the callback sees the last one, so that progress displays start
    there); the driver state, or None when the callback stops."""
    c = run.curve
    run.special, run.special_states = list(restored.special), list(restored.special_states)
    run.points = list(restored.points[:-1])
    run.reported = len(run.points)
    if run.bar is not None:
        run.bar.update(len(run.points))
    if not run.add_point(restored.points[-1]):
        return None
    X_prev = None if restored.X_prev is None else c.from_state(restored.X_prev)
    return c.from_state(restored.X), X_prev, c.from_state(restored.tau), restored.tests, restored.ds


def _loop(run: _Run, X0: Any, tau0: Any, restored: Any = None) -> tuple[Outcome, str]:
    c, s = run.curve, run.s
    algo = s.algorithm
    X_prev = None
    ds = s.ds
    if restored is not None:
        state = _resume(run, restored)
        if state is None:
            return Outcome.STOPPED, "stopped by the callback"
        X, X_prev, tau, tests, ds = state
    elif tau0 is None:
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
            # how far lam may move: ds bounds it where lam is part of the arclength; dlam_max, where it is set,
            # is the tighter bound when the metric holds other large terms (the period of a cycle)
            moved, reach = abs(c.lam(sol.x) - c.lam(X0)), min(s.ds, s.dlam_max)
            if moved > reach:  # no fold next to the start: the correction found another part of the curve
                return Outcome.START_FAILED, (f"start point did not converge at lam = {c.lam(X0):.6g}; along its "
                                              f"null tangent it went to lam = {c.lam(sol.x):.6g}, farther than "
                                              f"min(ds, dlam_max) = {reach:g}: no solution (and no fold) next to "
                                              f"the start")
            X, tau = sol.x, c.scale(sol.aux, float(s.direction))
        an = c.analyse(X, lin, tau)
        tests = c.tests(an, run.tangent_lam(tau))
        if _violates(c, tests):
            return _monitor_end(run, X, None, 0.0, None, tests, X, an)
        if not run.accept(c.record(X, an, int(sol.iterations), 0.0, run.tangent_lam(tau)), X, None, tau, tests, ds):
            return Outcome.STOPPED, "stopped by the callback"
    else:
        X, tau, tests = X0, tau0, None
    refined = 0  # halvings for an event that could not be located, counted until the event is passed
    ds_unrefined = ds  # the step before those halvings
    dlam_start = min(s.dlam_max, _chord_dlam(s))
    # rows of the last two steps' end points (the start counts when it was recorded), for chord_tol
    ends = [len(run.points) - 1] if run.points else []
    if restored is not None and restored.driver.get("ended"):
        # the last step written ended the branch (its end row, e.g. a Hopf point where the family ends), but the
        # run was interrupted before it recorded the end: nothing follows that row
        return Outcome(restored.driver["ended"]), str(restored.driver.get("message", ""))
    if restored is not None and restored.driver:
        refined, ds_unrefined = int(restored.driver["refined"]), float(restored.driver["ds_unrefined"])
        ends = [int(restored.driver[k]) for k in ("end0", "end1") if restored.driver.get(k, -1) >= 0]
    plotted = _PlottedRange()
    spectrum_halvings = 0  # of the step being tried, for a spectrum that moved too far (_untracked)
    while len(run.points) < s.max_points:
        # until the chord test has its three points it knows no curvature: the first steps are capped instead
        pred, con, ds, direction = algo.predict(c, X, X_prev, tau, ds, s.direction,
                                                s.dlam_max if len(ends) == 2 else dlam_start)
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
        onto = c.collapsed(Xn, X, X_prev)
        if onto is not None:
            # the step passed the point where the family is born (a Hopf point: zero amplitude; a period doubling:
            # the cycle of half the period) and the correction landed on what it was born from (which solves the
            # cycles' equations too, with no fold to signal it): shorter steps approach the end until the halvings
            # are spent, then the branch ends there
            if _can_refine(s, ds, refined):
                ds, refined, ds_unrefined = _refine(ds, refined, ds_unrefined)
                continue
            how = (f"no cycle in the step of ds = {ds:.3g} from lam = {c.lam(X):.6g}, the last cycle, to "
                   f"{c.lam(Xn):.6g}")
            return _end_unlocated(run, X, Xn, c.analyse(Xn, lin, tau_n), tau_n, int(sol.iterations), ds, onto, [],
                                  how)
        passed = c.passed_end(X, Xn)
        if passed is not None and _can_refine(s, ds, refined):
            # the step ran through the family's end onto its mirror image (the same cycles): an event between X and
            # the end has its image beyond it, and the two cancel in the test functions (a fold next to the end is
            # crossed twice, and its multiplier through +1 is then read as a BPC); shorter steps approach the end
            # until the halvings are spent, and the last one locates it (a fold, or a BPC, at zero amplitude)
            ds, refined, ds_unrefined = _refine(ds, refined, ds_unrefined)
            continue
        if _angle(c, tau, tau_n) > s.max_angle and 0.5 * ds >= s.ds_min:
            ds *= 0.5  # the tangent turned too far: a jump to another branch, or a bend the step does not resolve
            continue
        chord = None  # the chord test's factor on this step (chord_tol)
        if math.isfinite(s.chord_tol) and len(ends) == 2:
            last3 = [_plotted(run.points[i]) for i in ends] + [c.plotted(Xn)]
            chord = _chord_factor(last3, plotted.update(run.points), s.chord_tol)
            if chord < CHORD_RETRY and 0.5 * ds >= s.ds_min:
                # the step overshot a bend (its chord misses the curve by more than 2 chord_tol): retry shorter,
                # as the last points' curvature, which set this step, did not announce it
                ds = max(chord, 0.25, s.ds_min / ds) * ds
                continue
        ds_taken = ds
        bound = _crossed_bound(s, c.lam(X), c.lam(Xn))
        if bound is not None and abs(c.lam(X) - bound) <= 1e-12 * max(1.0, abs(bound)):
            # already on it (a branch resumed after its last point, or a step that landed on it to rounding)
            return Outcome.REACHED_END, f"lam = {bound:.6g} reached (bounds [lam_min, lam_max] = [{s.lam_min:g}, " \
                                        f"{s.lam_max:g}])"
        if bound is not None:  # place the last point on the bound: nothing is recorded or detected beyond it
            placed = _on_bound(c, X, Xn, tau, bound)
            if placed is None:
                return Outcome.REACHED_END, (f"lam = {c.lam(Xn):.6g} left [lam_min, lam_max] = [{s.lam_min:g}, "
                                             f"{s.lam_max:g}]; the point on the bound did not converge")
            sol, lin, tau_n = placed
            Xn = sol.x
        an_n = c.analyse(Xn, lin, tau_n)
        tests_n = c.tests(an_n, run.tangent_lam(tau_n))
        if _violates(c, tests_n):
            # the events of this step are not sought: the ones before the crossing are lost (rare; the steps
            # are short where a cycle grows into contact)
            return _monitor_end(run, X, direction, ds, tests, tests_n, Xn, an_n)
        if s.detect and spectrum_halvings < s.event_refine and 0.5 * ds >= s.ds_min and _untracked(c, tests, tests_n):
            # the spectrum moved too far in the step to be matched across the boundary: one member may have left the
            # stable side while another entered, which no count or sign shows; a shorter step matches it (as the
            # angle test, a control of the step, with its own count: at most event_refine halvings per step)
            ds, spectrum_halvings = 0.5 * ds, spectrum_halvings + 1
            continue
        found = []
        if tests is not None and s.detect:
            found = [f for f in (localise(run, kind, X, direction, ds, tests, tests_n, Xn, an_n)
                                 for kind in c.events(tests, tests_n, s.detect)) if f is not None]
        jump = next((f for f in found if f.jumped), None)
        if jump is not None:
            # the step went from one branch to another (its test functions change sign between two solutions that
            # stay apart however close the bracket): no event, a step too long for the curve's bend
            if 0.5 * ds >= s.ds_min:
                ds *= 0.5
                continue
            return Outcome.STEP_TOO_SMALL, (f"the correction jumps to another branch between lam = {c.lam(X):.6g} "
                                            f"and {c.lam(Xn):.6g} (the {jump.kind} test function changes sign "
                                            f"across the gap): no step above ds_min = {s.ds_min:g} stays on "
                                            f"this branch")
        # located, or bracketed (a subcritical family's fold test can jump there): a fold, or a branch point (the
        # BPC test vanishes at a Hopf or PD end too: a multiplier exp(i omega T) = 1, or (-1)^2), at zero amplitude
        # or zero distance from the half-period shift
        ending = next(((f, d) for f in found if f.kind in ("LPC", "BPC") and (f.located or np.isfinite(f.residual))
                       for d in [c.family_ends(f.point, X, Xn)] if d is not None), None)
        if ending is not None:
            return _end_of_family(run, *ending, found, X, ds)
        if passed is not None:
            # through the end in the shortest step, but no fold or branch point located there (not detected, not
            # sought at the first step, or cancelled again): the end lies on the path between X and Xn
            how = (f"passed in the step from lam = {c.lam(X):.6g} to {c.lam(Xn):.6g} onto the same cycles "
                   "shifted by half a period")
            return _end_unlocated(run, X, Xn, an_n, tau_n, int(sol.iterations), ds, passed, found, how)
        unlocated = any(not f.located and not (f.singular and f.kind in SINGULAR_EVENTS) for f in found)
        # the branch's first point stands for itself: a member on the boundary there (a start at a fold) is where
        # the branch begins, not a crossing still to come
        start_reported = len(run.points) <= 1 or any(p.index == len(run.points) - 1 and p.lam == c.lam(X)
                                                     for p in run.special)
        missing = _unexplained(c, tests, tests_n, s.detect, found, start_reported)
        if (unlocated and s.locate and direction is not None or missing) and _can_refine(s, ds, refined):
            # an event that cannot be located: the step may have jumped to another branch (the test functions
            # then change sign without passing through zero), or the test function is not resolved; a shorter
            # step tells the two apart.  More crossings than sign changes: two events in one step cancelled in
            # one test function (two pairs leaving the circle, or one leaving while another enters, seen by
            # matching); a shorter step separates them
            ds, refined, ds_unrefined = _refine(ds, refined, ds_unrefined)
            continue
        if missing and s.detect:  # refined as far as allowed: report, unlocated, what crossed
            found += [f for f in _unresolved(run, missing, X, Xn, an_n, tests.get("CRITICAL"), ds)
                      if f.kind in s.detect]
        # in the order of the branch: rows stay monotone in s, and an event at the step's end keeps its row index
        for f in sorted(found, key=lambda f: f.s if np.isfinite(f.s) else math.inf):
            _insert(run, f)
        if found or ds >= ds_unrefined:
            # only now: a halved step that stops short of the event would otherwise restart the count, and the
            # steps would creep towards an event the corrector cannot reach (a branch point) until ds < ds_min
            refined = 0
        rec = c.record(Xn, an_n, int(sol.iterations), ds, run.tangent_lam(tau_n))
        spectrum_halvings = 0
        X_prev, X, tau, tests = X, Xn, tau_n, tests_n
        X, tau, X_prev, tests = c.adapt(X, tau, X_prev, tests, len(run.points) + 1)
        ds = min(ds * s.grow, s.ds_max) if int(sol.iterations) <= s.fast_iter else ds
        if chord is not None:  # never below ds_min: a bend the step cannot resolve further is passed at ds_min
            ds = max(min(ds, max(0.5, chord) * ds_taken), s.ds_min)
        ends = (ends + [len(run.points)])[-2:]  # rec's row once accepted
        state = {"refined": refined, "ds_unrefined": ds_unrefined,
                 **{f"end{i}": float(row) for i, row in enumerate(ends)}}
        if not run.accept(rec, X, X_prev, tau, tests, ds, state):
            return Outcome.STOPPED, "stopped by the callback"
        if bound is not None:
            return Outcome.REACHED_END, f"lam = {bound:.6g} reached (bounds [lam_min, lam_max] = [{s.lam_min:g}, " \
                                        f"{s.lam_max:g}])"
    return Outcome.MAX_POINTS, f"max_points = {s.max_points} reached"


def _can_refine(s: Any, ds: float, refined: int) -> bool:
    """Whether a step may still be halved for an event (``event_refine`` halvings, not below ``ds_min``)."""
    return refined < s.event_refine and 0.5 * ds >= s.ds_min


def _refine(ds: float, refined: int, ds_unrefined: float) -> tuple[float, int, float]:
    """The step halved for an event: (ds, refined, ds_unrefined), the last the step before the first halving."""
    return 0.5 * ds, refined + 1, (ds if refined == 0 else ds_unrefined)


def _unexplained(c: Curve, tests: dict | None, tests_n: dict, detect: tuple = (), found: list = (),
                 start_reported: bool = True) -> int:
    """How many more eigenvalues (multipliers) crossed into or out of the unstable side over the step than the
    events account for: by the change of the unstable count, or by matching the members nearest the boundary (a
    pair out while another comes in leaves the count as it was).  A sign change accounts for its crossings only
    when it survived classification (among ``found``) or is not among the ``detect``-ed kinds: a sign change
    classified away (two real eigenvalues through 0 change the Hopf test's sign like a neutral saddle) explains
    nothing.  ``start_reported``: members on the boundary at the step's first point were reported there (an
    event sits on that point); otherwise they still have to cross in this step.  0 when the test data carry no
    count."""
    if tests is None or "UNSTABLE" not in tests or "UNSTABLE" not in tests_n or not c.event_weights:
        return 0
    kept = {f.kind for f in found}
    kinds = [k for k in c.events(tests, tests_n, tuple(c.event_weights)) if k not in detect or k in kept]
    explained = sum(c.event_weights[k] for k in kinds)
    matched = (c.crossings(tests["CRITICAL"], tests_n["CRITICAL"])
               if "CRITICAL" in tests and "CRITICAL" in tests_n else 0)
    return max(0, max(_crossings(tests, tests_n, start_reported), matched) - explained,
               _odd_one_out(tests, tests_n, kinds, explained))


def _untracked(c: Curve, tests: dict | None, tests_n: dict) -> bool:
    """:meth:`Curve.untracked` between the step's two points (False without their ``CRITICAL`` members)."""
    return tests is not None and "CRITICAL" in tests and "CRITICAL" in tests_n and \
        c.untracked(tests["CRITICAL"], tests_n["CRITICAL"])


#: events whose member need not cross the boundary: along a side branch that turns at a branch point the critical
#: eigenvalue (multiplier) touches it and goes back
_TOUCHING = frozenset({"BP", "BPC"})


def _odd_one_out(tests: dict, tests_n: dict, kinds: list[str], explained: int) -> int:
    """1 when the events found cannot be all that crossed, by parity: each real member through the boundary
    changes the unstable count by one and each complex pair by two, so the count's change and the crossings of
    the events found (their weights) have the same parity.  A fold with the unstable count unchanged hides a second
    real crossing the other way (a branch point of cycles one step from a fold, whose multiplier through +1
    cancels the fold's in the BPC test, while nearest-neighbour matching pairs the two multipliers wrongly: a new
    user's audit).  Not decided where a member lies on the boundary at either end (its side is arbitrary), nor
    when a branch point is among the events (its member may only touch the boundary)."""
    if tests.get("BOUNDARY", 0.0) or tests_n.get("BOUNDARY", 0.0) or _TOUCHING.intersection(kinds):
        return 0
    return int((int(tests_n["UNSTABLE"] - tests["UNSTABLE"]) - explained) % 2)


def _crossings(tests: dict, tests_n: dict, start_reported: bool = True) -> int:
    """The fewest crossings of the stability boundary between two points: the change of the "UNSTABLE" count,
    less the members lying on the boundary at either point ("BOUNDARY"; a point exactly on an event counts its
    critical eigenvalue on whichever side the test function's sign puts it), at the first point only when an
    event was reported there (else nothing has accounted for them: a step landing on a double Hopf point, whose
    test function keeps its sign over both steps, tests/cont/test_cont_events.py)."""
    slack = (tests.get("BOUNDARY", 0.0) if start_reported else 0.0) + tests_n.get("BOUNDARY", 0.0)
    return int(max(0.0, abs(tests_n["UNSTABLE"] - tests["UNSTABLE"]) - slack))


def _unresolved(run: _Run, missing: int, X: Any, Xn: Any, an_n: dict, before: np.ndarray | None,
                ds: float) -> list:
    """Unlocated special points (at the point after the step) for ``missing`` crossings that
    :func:`_unexplained` still finds after the last refinement: events closer than ``ds_min`` or
    ``ds / 2^event_refine`` (a double Hopf, two pairs crossing in opposite directions) that no test function's
    sign change accounts for.  Reported, not located, rather than left to a silent flip of the stability flag;
    named from the members that crossed (:meth:`Curve.crossing_kinds`); the step bounds where
    (:func:`._localise.step_span`)."""
    c = run.curve
    out = []
    for kind, own in c.crossing_kinds(an_n, missing, before):
        extra = c.special(kind, Xn, an_n, located=False)
        out.append(Found(kind, Xn, an_n, False, math.nan, {**({} if extra is None else extra), **own},
                          lam_error=step_span(c, kind, X, Xn, ds)))
    return out


def _violates(c: Curve, tests: dict) -> bool:
    """A stopping monitor at or below its minimum."""
    return c.monitor is not None and c.monitor.stop and not tests["MONITOR"] > 0.0


#: Relative floor of the scale of a plotted quantity in :func:`_chord_factor`: until a quantity has varied by a
#: tenth of its size, its scale is that tenth, so that the first points of a branch (whose range so far is small)
#: are not resolved as if that small range filled the plot, nor is the noise of the discretisation.
CHORD_FLOOR = 0.1
#: And at least this fraction of the largest recorded component: a component that varies at round-off level next to
#: zero (a residual, a symmetric state) is noise to the test, not a curve filling the plot (review of session 15: such
#: a component held a branch for 3000 points).  Quantities of a physical size (the GFB positions) are far above it.
CHORD_ROUNDOFF = 1e-6
#: A step whose chord factor is below this is retried (its chord misses the curve by more than 1 / CHORD_RETRY^2
#: = 2 chord_tol): the curvature that set the step came from the points before it.
CHORD_RETRY = 1.0 / math.sqrt(2.0)


def _plotted(rec: PointRecord) -> np.ndarray:
    """What a plot of the branch shows of one recorded point: lam, the recorded components' maxima and minima."""
    return np.concatenate([[rec.lam], np.ravel(rec.xmax), np.ravel(rec.xmin)])


def _chord_dlam(s: Any) -> float:
    """The largest change of lam in a step taken before the chord test has three points (the first step after a
    recorded start, the first two from a Hopf point), under ``chord_tol`` with finite bounds: sqrt(chord_tol) of the range [lam_min, lam_max], the step whose chord misses a parabola that
    spans the plot (y = 4 x (1 - x) in the scaled plane, curvature 8) by chord_tol.  Without it the first steps
    would follow ds and dlam_max alone, and a short range could be crossed in one step; inf otherwise."""
    if not (math.isfinite(s.chord_tol) and math.isfinite(s.lam_min) and math.isfinite(s.lam_max)):
        return math.inf
    return math.sqrt(s.chord_tol) * (s.lam_max - s.lam_min)


class _PlottedRange:
    """The smallest and largest value of each plotted quantity (:func:`_plotted`) over the rows so far, kept up to
    date as rows are appended (a rescan of every row at every step cost 6.3 s at 2000 points)."""

    def __init__(self) -> None:
        self.seen, self.lo, self.hi = 0, None, None

    def update(self, points: list[PointRecord]) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) over ``points``, of which the first ``seen`` were read before (rows are only appended)."""
        if len(points) > self.seen:
            Y = np.array([_plotted(r) for r in points[self.seen:]])
            lo, hi = Y.min(axis=0), Y.max(axis=0)
            self.lo = lo if self.lo is None else np.minimum(self.lo, lo)
            self.hi = hi if self.hi is None else np.maximum(self.hi, hi)
            self.seen = len(points)
        return self.lo, self.hi


def _chord_factor(last3: list[np.ndarray], extent: tuple[np.ndarray, np.ndarray], tol: float) -> float:
    """Factor on the step just taken that resolves the branch to ``tol`` (``chord_tol``): straight lines between
    recorded points stay within ``tol`` of the curve.  ``last3``: :func:`_plotted` of the last three step end
    points (the new one last), ``extent``: the smallest and largest value of each plotted quantity over the rows
    so far (:class:`_PlottedRange`).

    Each plotted quantity is scaled by its range over the rows so far (as a plot's axes are; at least
    :data:`CHORD_FLOOR` of its size, and a component at least :data:`CHORD_ROUNDOFF` of the largest one).  In that space the middle of the three points lies d from the chord of the
    outer two, and d = kappa h1 h2 / 2 for a curvature kappa and chords h1, h2.  A chord of length h misses the
    curve by at most kappa h^2 / 8, so a chord may be h = sqrt(8 tol / kappa) long: the factor is that over h2
    (inf on a straight line).
    """
    lo, hi = np.minimum(extent[0], last3[-1]), np.maximum(extent[1], last3[-1])
    size = np.maximum(np.abs(lo), np.abs(hi))
    scale = np.maximum(hi - lo, CHORD_FLOOR * size)
    scale[1:] = np.maximum(scale[1:], CHORD_ROUNDOFF * np.max(size[1:], initial=0.0))
    scale[scale == 0.0] = 1.0
    q0, q1, q2 = (q / scale for q in last3)
    h1, h2 = float(np.linalg.norm(q1 - q0)), float(np.linalg.norm(q2 - q1))
    chord = q2 - q0
    span = float(np.linalg.norm(chord))
    if not (h1 > 0.0 and h2 > 0.0 and span > 0.0):
        return math.inf
    a = q1 - q0
    d = float(np.linalg.norm(a - (a @ chord) / span**2 * chord))
    if not d > 0.0:
        return math.inf
    return math.sqrt(4.0 * tol * h1 / (d * h2))


def _angle(c: Curve, a: Any, b: Any) -> float:
    """Angle [rad] between two tangents in the curve's inner product."""
    den = math.sqrt(max(c.inner(a, a) * c.inner(b, b), 0.0))
    if not den > 0.0:
        return 0.0
    return math.acos(min(1.0, max(-1.0, c.inner(a, b) / den)))


def _crossed_bound(s: Any, lam0: float, lam1: float) -> float | None:
    """The bound of [lam_min, lam_max] that the step lam0 -> lam1 reached or crossed (to rounding: steps that add
    up to the bound fall short of it by an ulp or so), if any."""
    def near(b):
        return 1e-12 * max(1.0, abs(b))
    if lam1 >= s.lam_max - near(s.lam_max) and s.lam_max > -np.inf and lam0 < s.lam_max - near(s.lam_max):
        return float(s.lam_max)
    if lam1 <= s.lam_min + near(s.lam_min) and s.lam_min < np.inf and lam0 > s.lam_min + near(s.lam_min):
        return float(s.lam_min)
    if not (s.lam_min <= lam1 <= s.lam_max):  # a step from a point on the bound (a resumed branch) leaving them
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


def _monitor_end(run: _Run, X: Any, tau: Any, ds: float, tests: dict | None, tests_n: dict, Xn: Any,
                 an_n: dict) -> tuple[Outcome, str]:
    """The branch crossed its monitor's bound: record the located crossing as its last point and end."""
    c, m = run.curve, run.curve.monitor

    def message(where: str) -> str:
        return (f"{m.name} fell to its bound {m.minimum:g}{' ' + m.unit if m.unit else ''} at {where}: beyond it "
                "the solutions leave the model's validity (Monitor.stop)")

    if tests is not None and tau is not None and run.s.locate:
        f = bracket(run, "MONITOR", X, tau, ds, tests, tests_n, Xn, an_n)
        if np.isfinite(f.residual):
            # the crossing is the last row: through accept, so that the callback sees it and the checkpoint holds
            # it with the end (a run interrupted before end.json is written resumes to this end)
            text = message(f"lam = {c.lam(f.point):.6g}")
            rec = c.record(f.point, f.analysis, f.iterations, f.s, f.tangent_lam)
            t = f.tangent if f.tangent is not None else tau
            if not run.accept(rec, f.point, X, t, c.tests(f.analysis, run.tangent_lam(t)), ds,
                              {"ended": str(Outcome.CONTACT), "message": text}):
                return Outcome.STOPPED, "stopped by the callback"
            return Outcome.CONTACT, text
    return Outcome.CONTACT, message(f"lam = {c.lam(X):.6g}" if tests is not None else "the start")


#: The outcome and the wording of a family's end, by the type of the point where it was born.
_ENDS = {"HOPF": (Outcome.ENDED_AT_HOPF, "shrank to an equilibrium", "a Hopf point", "its equilibria"),
         "PD": (Outcome.ENDED_AT_PD, "shrank onto the cycle of half their period", "a period doubling",
                "the cycles of half the period")}


def _end_of_family(run: _Run, f: Found, data: dict[str, Any], found: list[Found], X: Any, ds: float,
                   message: str | None = None) -> tuple[Outcome, str]:
    """End the branch at the point ``f`` where its cycles shrank onto what they were born from (``data["type"]``:
    a Hopf point, or a period doubling of the cycles of half the period): a fold test changes sign there only
    because the discrete family runs on through it, back along itself (the same cycles: the amplitude's or the
    half-period shift's sign flips).  The events before it in the step are inserted, the end is the last row
    (located or bracketed as the fold was), and the rest is not recorded."""
    c = run.curve
    data = dict(data)
    kind = data.pop("type")
    outcome, shrank, point, continuing = _ENDS[kind]
    lam = float(c.lam(f.point)) if f.lam is None else f.lam
    for g in sorted((g for g in found if g is not f and np.isfinite(g.s) and g.s < f.s), key=lambda g: g.s):
        _insert(run, g)
    rec = c.record(f.point, f.analysis, f.iterations, f.s, f.tangent_lam)
    run.special_states.append(c.state(f.point))
    run.special.append(SpecialPoint(type=kind, lam=lam, index=len(run.points),
                                    spectrum=np.asarray(f.analysis["spectrum"]), located=f.located, residual=f.residual,
                                    lam_error=f.lam_error, state=len(run.special_states) - 1, **data))
    message = message or (f"the cycles {shrank} at lam = {lam:.6g}: {point}, where the family ends ({continuing} "
                          "continue there)")
    # the end goes into the step itself: a run interrupted after writing it resumes to this end, not past it
    state = {"ended": str(outcome), "message": message}
    if not run.accept(rec, f.point, X, f.tangent, c.tests(f.analysis, f.tangent_lam), ds, state):
        return Outcome.STOPPED, "stopped by the callback"
    return outcome, message


def _end_unlocated(run: _Run, X: Any, Xn: Any, an: dict, tau_n: Any, iterations: int, ds: float,
                   data: dict[str, Any], found: list[Found], how: str) -> tuple[Outcome, str]:
    """End the branch whose shortest step from X to Xn went past the point where the family was born without
    locating it: the correction collapsed onto what the family was born from (:meth:`Curve.collapsed`), or ran
    through the end onto its mirror image (:meth:`Curve.passed_end`).  The row is Xn (analysis ``an``), the end
    not located; its ``lam`` and ``lam_error`` are the curve's estimate in ``data`` (lam turns at the end, so the
    end can lie outside the step's span in lam).  ``how``: the step, in words, for the message."""
    data = dict(data)
    lam, lam_error = data.pop("lam"), data.pop("lam_error")
    f = Found(data["type"], Xn, an, False, math.nan, {}, iterations=iterations, s=ds,
              tangent_lam=run.tangent_lam(tau_n), tangent=tau_n, lam_error=lam_error, lam=lam)
    _, shrank, point, continuing = _ENDS[data["type"]]
    message = (f"the cycles {shrank} near lam = {lam:.6g} +- {lam_error:.2g} ({how}): the family ends at {point} "
               f"there ({continuing} continue there)")
    # a fold or branch point found where the orbit has shrunk onto the end is the end's own sign change (lam turns
    # there, and a multiplier is 1 there), not an event of its own
    c = run.curve
    found = [g for g in found if not (g.kind in ("LPC", "BPC") and c.family_ends(g.point, X, Xn) is not None)]
    return _end_of_family(run, f, data, found, X, ds, message)


def _own_member(run: _Run, f: Found) -> None:
    """A second event of the same type at the same point (a step landing exactly on a double Hopf or double NS
    point: each crossing pair's zero is found at that end) takes the next crossing member's data (omega, angle):
    :meth:`Curve.special` reads the one pair nearest the boundary, which the first event already carries."""
    same = [p for p in run.special if p.type == f.kind and p.lam == run.curve.lam(f.point)]
    keys = [k for k in ("omega", "angle") if f.extra.get(k) is not None]
    if not same or not keys:
        return
    used = [[getattr(p, k) for k in keys] for p in same]
    for kind, own in run.curve.crossing_kinds(f.analysis, 2 * (len(same) + 1)):
        vals = [own.get(k) for k in keys]
        if kind == f.kind and None not in vals and not any(np.allclose(vals, u, rtol=1e-6, atol=1e-9) for u in used):
            f.extra.update(own)
            return


def _insert(run: _Run, f: Found) -> None:
    """Insert a special point (a bracketed one also as a new row of the branch)."""
    c = run.curve
    row = len(run.points)  # the point after the step, recorded next
    if f.end == "left":  # the step's first point, already recorded
        row -= 1
    elif np.isfinite(f.residual) and f.end is None:
        run.points.append(c.record(f.point, f.analysis, f.iterations, f.s, f.tangent_lam))
        row = len(run.points) - 1
    _own_member(run, f)
    add_discretisation_error(run, f)
    run.special_states.append(c.state(f.point))
    lam = float(c.lam(f.point) if f.lam is None else f.lam)
    run.special.append(SpecialPoint(type=f.kind, lam=lam, index=row, spectrum=np.asarray(f.analysis["spectrum"]),
                                    located=f.located, residual=f.residual, lam_error=f.lam_error,
                                    state=len(run.special_states) - 1, **f.extra))
