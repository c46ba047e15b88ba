r"""Localisation of the events of one continuation step, and the error of each located point in lam.

Between a step's ends X (left) and Xn, a test function that changes sign is driven to zero by the Illinois regula
falsi (:func:`locate`) in the arclength s from X, each evaluation a full correction on the hyperplane at distance s
along X's tangent (:func:`bracket`).  What comes out is a :class:`Found`: located (the test function is zero to
``locate_tol``), bracketed (it jumps across a closed bracket), or not localised; with its estimated error in lam:

* the residual's share, |residual / slope| in s times the tangent's lam component;
* the bracket's width in s, for a bracketed point;
* the discretisation's share (:func:`add_discretisation_error`): the largest move of the zero on the curve's
  other discretisations (cycles: every mesh interval halved, and the mesh staggered by half an interval);
* for a branch point whose corrections fail next to it: where a regular bordered test function, interpolated
  across the gap, vanishes (:func:`_across_the_gap`).

The driver (:mod:`._driver`) decides what to do with each: insert it, refine the step, or report it unlocated.
Nothing here knows whether the curve holds cycles or equilibria; it sees the :class:`~._driver.Curve` protocol
through ``run.curve`` and the settings through ``run.s``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
from scipy.optimize import brentq

__all__ = ["Found", "SINGULAR_EVENTS", "add_discretisation_error", "bracket", "localise", "locate", "step_span"]

#: events at which lam turns: inside a step their lam lies beyond the step's ends, by up to the step itself
TURNING = ("FOLD", "LPC")


def step_span(c: Any, kind: str, X: Any, Xn: Any, ds: float) -> float:
    """How far in lam an event that lies somewhere in the step X -> Xn (arclength ``ds``) can be from its ends: the
    step's change in lam, or for a fold, where lam turns inside the step, the step ``ds`` (lam is a unit-weight
    component of the arclength, so it moves by at most ds)."""
    return float(ds) if kind in TURNING else abs(c.lam(Xn) - c.lam(X))


#: Events at which the extended Jacobian itself is singular (a second branch through the point): the corrections
#: that would locate them fail close to them, and their test function (a multiplier through +1 beside the trivial
#: one) is computed only to ~sqrt(eps) there, so one left unlocated *for either reason* is no sign of a bad step
#: and is not refined (one whose test function jumps still is: a jump to another branch).
SINGULAR_EVENTS = ("BP", "BPC")

#: :func:`locate`'s noise test: a bracket narrower than |g| / (NOISE_SPAN * the step's mean slope) holds a value that
#: no test function steeper than NOISE_SPAN times its mean slope reaches inside it: g is noise (or a jump) there.
NOISE_SPAN = 100.0


def locate(g: Callable[[float], tuple[float, Any]], s_hi: float, g_lo: float, g_hi: float, *,
           tol: float = 1e-9, s_tol: float = 1e-10, max_iter: int = 30,
           info: dict | None = None, noise_stop: bool = False) -> tuple[float, Any, float, bool]:
    """Zero of g(s) on (0, s_hi) by the Illinois regula falsi.

    ``g(s)`` returns (value, payload) and may return (nan, None) on failure.  Returns (s, payload, value,
    located): located when |g| <= tol times the larger end value (when that is below 1: then s is found to about
    tol times s_hi, whatever the test function's scale), or when the bracket has shrunk below s_tol * s_hi with
    |g| below 1e-6 of its end values (a continuous root); not located when g jumps across a closed bracket, when
    g_lo and g_hi do not bracket a zero (no evaluation then) or when the iteration budget runs out.  With
    ``noise_stop``, also not located, and ``info["noise"]`` set, as soon as the bracket is narrower than |g| over
    :data:`NOISE_SPAN` times the mean slope (g_hi - g_lo) / s_hi while |g| is below 1e-3 of the end values: the
    test function has hit its noise floor (a branch point's, ~sqrt(eps)), and narrowing the bracket further, down
    to s_tol, would not say where its zero is better than |g / slope| (the error the caller then reports).  An end value
    already within ``tol`` is returned after one evaluation there (the point on the event) when a value just
    inside the end (1e-6 s_hi) shows no sign change in the interior.  ``info``, when given, receives
    ``"bracket"``: the last (a, b) known to hold the sign change (what an unlocated result is worth).
    """
    a, b, ga, gb = 0.0, float(s_hi), float(g_lo), float(g_hi)
    info = {} if info is None else info

    def done(*result):
        info["bracket"] = (min(a, b), max(a, b))
        return result

    if not (np.sign(ga) * np.sign(gb) <= 0):
        return done(b, None, gb, False)
    # relative to the end values where they are small: a test function that is itself small across the step (a
    # product of factors of which only one vanishes) would meet an absolute tolerance far from its zero
    tol = tol * min(1.0, max(abs(ga), abs(gb)))
    # An end point on a zero (a point landing on an event): the regula falsi would only creep towards it.  But the
    # end value can vanish for another reason than the crossing (a second event's factor of a product test function
    # zero there, while the first crosses inside): a value just inside the end on the far end's side says that no
    # sign change lies inside, and the end is the event; otherwise the interior is searched, without the end.
    inset = 1e-6 * b
    if abs(gb) <= tol:
        gi, payload = g(b - inset)
        if np.isfinite(gi) and np.sign(gi) == np.sign(ga):
            gs, payload = g(b)
            if np.isfinite(gs):
                return done(b, payload, gs, abs(gs) <= tol)
        elif np.isfinite(gi) and np.sign(gi) * np.sign(ga) < 0:
            b, gb = b - inset, gi
    if abs(ga) <= tol:
        gi, payload = g(a + inset)
        if np.isfinite(gi) and np.sign(gi) == np.sign(gb):
            gs, payload = g(a)
            if np.isfinite(gs):
                return done(a, payload, gs, abs(gs) <= tol)
        elif np.isfinite(gi) and np.sign(gi) * np.sign(gb) < 0:
            a, ga = a + inset, gi
    side = 0
    best = (b, None, gb)
    mean_slope = abs(float(g_hi) - float(g_lo)) / float(s_hi)
    small = 1e-3 * max(abs(float(g_lo)), abs(float(g_hi)))
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
                return done(best[0], best[1], best[2], False)
        best = (s, payload, gs)
        if abs(gs) <= tol:
            return done(s, payload, gs, True)
        if abs(b - a) <= s_tol * max(1.0, abs(s_hi)):
            # The bracket closed.  A continuous test function is then tiny next to its values at the ends; one that
            # jumps across the bracket (a critical eigenvalue swapping, a discontinuous model) is not: bracketed,
            # not located.
            return done(s, payload, gs, abs(gs) <= 1e-6 * max(abs(g_lo), abs(g_hi)))
        if noise_stop and abs(gs) <= small and abs(b - a) * NOISE_SPAN * mean_slope < abs(gs):
            info["noise"] = True
            return done(s, payload, gs, False)
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
    return done(best[0], best[1], best[2], False)


@dataclass
class Found:
    """An event of one step, localised (or not) but not yet inserted in the branch."""

    kind: str
    point: Any
    analysis: dict
    located: bool
    residual: float  # NaN: not bracketed (the point after the step stands for it)
    extra: dict
    iterations: int = 0
    s: float = math.nan
    tangent_lam: float = math.nan
    singular: bool = False  # not located because the corrections next to its zero failed (see bracket)
    jumped: bool = False  # the solution itself jumps across the closed bracket: two branches (see bracket)
    sides: tuple | None = None  # bracketed: (critical members before, analysis after) for the crossing's data
    lam_error: float = math.nan  # SpecialPoint.lam_error (the localisation's share until _insert)
    lam: float | None = None  # where it differs from the point's (a branch point placed across its gap)
    tangent: Any = None  # at the point (localised points)
    slope: float = math.nan  # of the test function in the arclength over the step
    scale: float = math.nan  # the larger test value at the step's ends
    end: str | None = None  # "left"/"right": the event is the step's first/last point itself (no new row)


def localise(run: Any, kind: str, X: Any, tau: Any, ds: float, tests: dict, tests_n: dict, Xn: Any,
              an_n: dict) -> Found | None:
    """Localise ``kind`` between X (left) and Xn; None when the sign change is no bifurcation (the curve's
    :meth:`Curve.special` says so, e.g. a real collision of multipliers)."""
    found = bracket(run, kind, X, tau, ds, tests, tests_n, Xn, an_n)
    extra = run.curve.special(kind, found.point, found.analysis, found.located, ends=(tests, tests_n))
    if extra is None:
        return None
    if found.sides is not None and any(k in extra for k in ("omega", "angle")):
        # bracketed: the point's data are those of one side, where the pair nearest the boundary need not be the
        # one that crossed (several pairs as near, a jump of the model); the member that changed side across the
        # bracket, by matching, gives the frequency or angle
        before, after = found.sides
        for k, data in run.curve.crossing_kinds(after, 2, before=before):
            if k == kind and data:
                extra = {**extra, **data}
                if "omega" in data and "period" in extra:  # a Hopf point's period is that of its pair
                    extra["period"] = 2.0 * math.pi / data["omega"]
                break
    found.extra = extra
    return found


def bracket(run: Any, kind: str, X: Any, tau: Any, ds: float, tests: dict, tests_n: dict, Xn: Any,
             an_n: dict) -> Found:
    """Drive the test function ``kind`` to zero between X (left) and Xn (regula falsi in the arclength)."""
    c, s = run.curve, run.s
    # not localised: somewhere in the step
    found = Found(kind, Xn, an_n, False, math.nan, {}, lam_error=step_span(c, kind, X, Xn, ds))
    failed = []
    info: dict = {}  # locate's report: the last bracket, and whether it stopped at the test function's noise
    if s.locate and tau is not None:
        # Every evaluation lies on the hyperplane at distance sv from X along tau; its guess comes from the
        # nearest point already on the branch, along that point's own tangent.  Next to a branch point, where the
        # corrections' basin shrinks with the distance to it, the step's linear predictor from X would start
        # outside it long before the bracket closes.
        near = [(0.0, X, tau)]
        solved: dict[float, tuple] = {}  # sv -> (solution, linearisation) of the converged evaluations

        def solve_at(sv):
            if sv in solved:
                return solved[sv]
            s0, P, t = min(near, key=lambda e: abs(e[0] - sv))
            along = c.inner(t, tau)
            pred = c.add(P, c.scale(t, (sv - s0) / along if along > 0.5 else sv - s0))
            sol, lin = c.correct(pred, c.palc_constraint(X, tau, sv, pred))
            if not sol.converged:
                failed.append(sv)
                return None
            near.append((sv, sol.x, sol.aux))
            solved[sv] = (sol, lin)
            return solved[sv]

        tested: dict[float, tuple] = {}  # sv -> (analysis, test values) of the evaluations

        def g(sv):
            got = solve_at(sv)
            if got is None:
                return float("nan"), None
            sol, lin = got
            a = c.analyse(sol.x, lin, sol.aux)
            tl = float(c.lam(sol.aux))
            tested[sv] = (a, c.tests(a, tl))
            return tested[sv][1][kind], (sol, a, tl)

        sv, payload, val, located = locate(g, ds, tests[kind], tests_n[kind], tol=s.locate_tol, info=info,
                                           noise_stop=True)
        if payload is not None:  # located, or bracketed where the test function jumps (residual not small)
            sol, an, tl = payload
            found = Found(kind, sol.x, an, bool(located), float(val), {}, int(sol.iterations), sv, tl,
                           end="left" if sv == 0.0 else "right" if sv == ds else None)
            # the test function's slope in the arclength, from the step's ends: enough for an error estimate
            found.slope = (tests_n[kind] - tests[kind]) / ds
            found.scale = max(abs(tests[kind]), abs(tests_n[kind]))
            found.tangent = sol.aux
            if located:
                found.lam_error = abs(tl * float(val) / found.slope) if found.slope else math.nan
            else:  # bracketed: where in the bracket the zero lies is unknown.  Its width in the arclength bounds
                # its width in lam (lam is a unit-weight component of the curve's norm); |tl| times it would not,
                # where lam turns (the side branch of a pitchfork at its branch point)
                lo, hi = info["bracket"]
                found.lam_error = hi - lo
                if info.get("noise") and found.slope:  # the zero of a noisy g is known to |g / slope| only
                    found.lam_error = max(found.lam_error, abs(float(val) / found.slope))
                found.jumped = _solution_jumps(c, [(0.0, X), (ds, Xn)] + [(k, v[0].x) for k, v in solved.items()],
                                               lo, hi)
                before = tests if lo == 0.0 else tested.get(lo, (None, {}))[1]
                after = an_n if hi == ds else tested.get(hi, (None, None))[0]
                if "CRITICAL" in before and after is not None:
                    found.sides = (before["CRITICAL"], after)
    # a branch point: the corrections failed only next to it, or its test function sank into its noise there,
    # where it had all but vanished (a jump to another branch makes the test function change sign far from zero,
    # with or without failures)
    blocked = bool(failed) or (bool(info.get("noise")) and kind in SINGULAR_EVENTS)
    found.singular = (blocked and not found.located and np.isfinite(found.residual)
                      and abs(found.residual) <= 1e-3 * max(abs(tests[kind]), abs(tests_n[kind])))
    if found.singular and found.slope:
        # There the test function is noise of size |residual| about its zero, resolved only to |residual / slope|
        # in s however tight the bracket: a multiplier through +1 next to the trivial one is computed to about the
        # square root of the rounding (3.6e-7 at the Brusselator's branch points, test_cont_brusselator.py).
        found.lam_error = max(found.lam_error, abs(found.residual / found.slope))
        across = _across_the_gap(run, solve_at, found.s, ds)
        if across is not None and across[1] < found.lam_error:
            found.lam, found.lam_error = across
    return found


def _solution_jumps(c: Any, points: list, lo: float, hi: float) -> bool:
    """Whether the corrected points at the ends of a bracket (lo, hi) of the arclength lie on two different
    branches.  Each point lies on the hyperplane at distance s from the step's first point along its tangent; along
    one branch two such points are about as far apart as the hyperplanes (hi - lo over the cosine of the angle
    between the branch and that tangent), and a test function may still jump between them (a mesh node crossing
    a kink of the vector field).  Where the hyperplanes cut two branches the points stay apart by the gap between
    them however close lo and hi: the step jumped, and the sign change is no event of either branch
    (x' = eps + p x - x^3 near its corner).  Ten times the bracket's width stands for an angle of 84 degrees (a step
    that does not resolve the branch, to be halved as well); the floor, 1e-6 of the point's size, lies far above
    the corrections' own error."""
    at = dict(points)
    if lo not in at or hi not in at:
        return False
    d = c.add(at[hi], c.scale(at[lo], -1.0))
    dist = math.sqrt(max(c.inner(d, d), 0.0))
    size = math.sqrt(max(c.inner(at[lo], at[lo]), 0.0))
    return dist > 10.0 * (hi - lo) and dist > 1e-6 * (1.0 + size)


def _across_the_gap(run: Any, solve_at: Callable, center: float, ds: float) -> tuple[float, float] | None:
    """(lam, error) of a branch point whose corrections fail next to it, from a regular test function
    interpolated across the gap; None where the curve has none or it does not apply.

    The test function that detected it is read off the spectrum (a multiplier through +1 beside the trivial one:
    noise of ~sqrt(eps)).  Here the branch point is where the augmented Jacobian A (the curve's equations and its
    continuation row) is singular, a property of A alone: with b fixed and c the unit vector along A^{-1} b next
    to it (at ``center``, the noisy test's zero, at arclength ``center`` in a step of ``ds``), h = -1 / (c . A^{-1}
    b) passes through zero linearly there (A^{-1} b, dominated by the null vector, turns round through infinity),
    and is computed to rounding wherever a correction converges (:meth:`Curve.border_solve`).  Far from it the
    sign of c . A^{-1} b says nothing, so a bracket is sought at distances doubling from ``center``; then the
    regula falsi on h tightens it as far as corrections converge (to ~1e-5 in s on the Brusselator: they fail
    within a few 1e-6 of the branch point), and the zero of the line through its ends is the estimate; its error,
    the largest distance to the zero of a parabola through both ends and an evaluation beyond either."""
    c = run.curve
    values: dict[float, tuple[float, float]] = {}  # sv -> (h, lam)
    cvec = []

    def h(sv):
        if sv in values:
            return values[sv][0], values[sv]
        got = solve_at(sv)
        w = None if got is None else c.border_solve(got[0].x, got[1])
        if w is None or not np.all(np.isfinite(w)):
            return float("nan"), None
        if not cvec:
            cvec.append(w / np.linalg.norm(w))
        d = float(np.dot(cvec[0], w))
        if d == 0.0:
            return float("nan"), None
        values[sv] = (-1.0 / d, c.lam(got[0].x))
        return values[sv][0], values[sv]

    if not np.isfinite(h(center)[0]):
        return None
    delta = 1e-6 * ds
    while True:
        lo, hi = max(center - delta, 0.0), min(center + delta, ds)
        h_lo, h_hi = h(lo)[0], h(hi)[0]
        if np.isfinite(h_lo) and np.isfinite(h_hi) and np.sign(h_lo) != np.sign(h_hi):
            break
        if (lo == 0.0 and hi == ds) or delta > 0.25 * ds:
            return None
        delta *= 4.0
    info: dict = {}
    sv, payload, val, located = locate(lambda u: h(lo + u), hi - lo, h_lo, h_hi, tol=1e-12, s_tol=1e-12,
                                       info=info)
    if located and payload is not None:
        return payload[1], 0.0
    a, b = (lo + u for u in info["bracket"])
    if a not in values or b not in values:
        return None
    (ha, la), (hb, lb) = values[a], values[b]
    lam_line = la + (lb - la) * ha / (ha - hb)
    # The error: the zero of the parabola through the bracket's ends and an evaluation beyond either end (one more
    # correction each, far enough from the branch point to converge), against the line's.
    w = b - a
    for extra in (a - w, b + w):
        if 0.0 <= extra <= ds and extra not in values:
            h(extra)
    worst = 0.0
    for extra in (a - w, b + w):
        if extra not in values:
            return lam_line, abs(lb - la)
        s3 = np.array([a, b, extra]) - a
        h3 = np.array([ha, hb, values[extra][0]])
        l3 = np.array([la, lb, values[extra][1]])
        roots = np.roots(np.polyfit(s3, h3, 2))
        roots = roots[np.isreal(roots)].real
        roots = roots[(roots >= 0.0) & (roots <= w)]
        if roots.size != 1:
            return lam_line, abs(lb - la)
        worst = max(worst, abs(float(np.polyval(np.polyfit(s3, l3, 2), roots[0])) - lam_line))
    return lam_line, worst


def _relocated_shift(run: Any, f: Found, X2: Any, t2: Any, max_iter: int = 16) -> float:
    """How far in lam the zero of the test function ``f.kind`` at the localised point ``f.point`` moves when the
    curve is computed on another discretisation (``X2``, ``t2``: the point and its tangent carried there,
    :meth:`Curve.other_discretisations`); NaN where that relocation fails.

    Why not the per-orbit mesh estimate: the location of a special point depends on the multipliers (or the
    tangent), whose discretisation error can be far larger than the orbit's.  On the GFB reference branch the
    orbit's estimate is ~5e-7 while the NS moves by ~1e-4 between meshes; at a kink of the vector field a fold
    moves by 1e-4 with a trivial multiplier exact to 1e-14.  The move to a mesh twice as fine is about the error of
    this one (all of it when the finer one is exact, half of it for a first-order method) where the error falls
    steadily with the mesh size; with a kink it does not, and a mesh as fine but placed differently samples it
    anew (see the cycles' ``other_discretisations``).

    The zero on the finer discretisation, in the arclength s along the carried tangent (each point corrected on
    the hyperplane at distance s from the carried point): secant steps from the step's slope until the sign
    changes, then Brent's method on that bracket (:func:`_bracketed_zero`), to a precision (1e-3 of the test
    function) that suits an error estimate.  The secant alone would wander where the discrete curve has corners
    (a mesh node crossing a kink makes the tangent, hence the fold test, jump).  A step that reduces the test
    function tenfold ends the search at once: the secant's zero is then accurate to far better than the move
    itself."""
    c, kind, slope = run.curve, f.kind, f.slope
    budget = [max_iter]

    def g(sv: float) -> tuple[float, Any]:
        budget[0] -= 1
        pred = c.add(X2, c.scale(t2, sv))
        s2, lin = c.correct(pred, c.palc_constraint(X2, t2, sv, pred))
        if not s2.converged:
            return math.nan, None
        return c.tests(c.analyse(s2.x, lin, s2.aux), float(c.lam(s2.aux)))[kind], c.lam(s2.x)

    s0, (g0, lam0) = 0.0, g(0.0)
    if not (np.isfinite(g0) and slope and np.isfinite(slope)):
        return math.nan
    if abs(g0) <= run.s.locate_tol * min(1.0, f.scale):
        # already a zero there (to the tolerance the point was located with); a double zero (two events at one
        # point) would offer the secant no sign change and no decrease
        return abs(lam0 - c.lam(f.point))
    s1 = -g0 / slope
    while budget[0] > 0:
        g1, lam1 = g(s1)
        if not np.isfinite(g1):
            return math.nan
        if abs(g1) <= 0.1 * abs(g0):
            # the last step took the test function down tenfold: it is straight here, and the zero is the
            # secant's, good to about a hundredth of the step (the usual case on a smooth problem: two corrections)
            lam_z = lam1 - g1 * (lam1 - lam0) / (g1 - g0) if g1 != g0 else lam1
            return abs(lam_z - c.lam(f.point))
        if np.sign(g1) != np.sign(g0):
            tol = 1e-3 * min(1.0, max(abs(g0), abs(g1)))
            lam_z = _bracketed_zero(g, {s0: (g0, lam0), s1: (g1, lam1)}, tol, budget)
            return abs(lam_z - c.lam(f.point))
        # same sign: a secant step, at most four times as long as the last one (a flat stretch would fling it)
        step = -g1 * (s1 - s0) / (g1 - g0) if g1 != g0 else 2.0 * (s1 - s0)
        step = float(np.clip(step, -4.0 * abs(s1 - s0), 4.0 * abs(s1 - s0)))
        s0, g0, lam0, s1 = s1, g1, lam1, s1 + step
    return math.nan


class _Stop(Exception):
    """Ends Brent's iteration of :func:`_bracketed_zero` from inside its function."""


def _bracketed_zero(g: Callable[[float], tuple[float, Any]], known: dict[float, tuple[float, float]], tol: float,
                    budget: list[int]) -> float:
    """lam where the test function ``g(s) -> (value, lam)`` vanishes between the two arclengths of ``known``
    ({s: (value, lam)}, values of opposite signs), by Brent's method (``scipy.optimize.brentq``: inverse quadratic
    and secant steps with bisection as the safeguard), ended as soon as a value is within ``tol``, or when the
    bracket has closed to 1e-4 of its first width.  When the bracket closes (on a jump, or a zero that the
    tolerance was not met at), ``budget`` (corrections left, decremented by ``g``) runs out, or a correction inside
    the bracket fails (``g`` gives NaN), the zero of the line through the ends of the narrowest sign change
    evaluated stands for it.

    Why not the Illinois regula falsi of :func:`locate`: next to a zero reached along a curved test function it
    keeps one end fixed and creeps; on the GFB's NS the staggered mesh's relocation took five corrections after the
    bracket, Brent's method four."""

    def value(sv: float) -> float:
        sv = float(sv)
        if sv not in known:
            if budget[0] <= 0:
                raise _Stop(None)
            v, lam = g(sv)
            if not np.isfinite(v):
                # a failed correction: the bracket evaluated so far still holds a zero
                raise _Stop(None)
            known[sv] = (float(v), float(lam))
        v, lam = known[sv]
        if abs(v) <= tol:
            raise _Stop(lam)
        return v

    lo, hi = sorted(known)
    try:
        # xtol relative to the bracket: an absolute one would leave a narrow bracket (a shift far below 1e-4 in s)
        # without a single evaluation inside
        brentq(value, lo, hi, xtol=1e-4 * (hi - lo), maxiter=100, disp=False)
    except _Stop as stop:
        if stop.args[0] is not None:
            return float(stop.args[0])
    # the narrowest sign change among the evaluations, its zero by the line through its ends
    pts = sorted(known.items())
    pairs = [(a, b) for a, b in zip(pts, pts[1:]) if np.sign(a[1][0]) != np.sign(b[1][0])]
    (_, (ga, la)), (_, (gb, lb)) = min(pairs, key=lambda p: p[1][0] - p[0][0])
    return la + (lb - la) * ga / (ga - gb)


def add_discretisation_error(run: Any, f: Found) -> None:
    """Add to ``f.lam_error`` the largest move of its zero on the curve's other discretisations
    (:func:`_relocated_shift` on each of :meth:`Curve.other_discretisations`); nothing for a curve without one, or next to a branch point (``f.singular``:
    the relocations would fail there as the corrections did).

    A jump of the test function (a mesh node crossing a kink of the vector field) closes the bracket to 1e-10
    while the exact zero lies 1e-4 away: the discretisation's share is added, located or not.  The estimate leaves
    the branch as it would be without it: the curve's memo (the Floquet method's warm start) is restored
    afterwards, so that a resumed branch, which does not repeat it, agrees to rounding."""
    c = run.curve
    if f.tangent is None or f.singular:
        return
    memo = getattr(c, "memo", None)
    saved = None if memo is None else dict(memo)
    shifts = [_relocated_shift(run, f, X2, t2) for X2, t2 in c.other_discretisations(f.point, f.tangent)]
    if memo is not None:
        memo.clear()
        memo.update(saved)
    if shifts:  # NaN (no estimate) only when every relocation failed
        finite = [v for v in shifts if np.isfinite(v)]
        f.lam_error += max(finite) if finite else math.nan
