r"""Bounded black-box optimisers over a few (2-4) real design variables, with evaluation counts and full history.

Two optimisers, both for expensive objectives (one evaluation = one limit-cycle solve, ~0.1-1 s), so both count
every evaluation, record it, treat failed evaluations as data rather than crashes, and return the work done so far
when interrupted (Ctrl-C):

* :func:`pattern_search` — generalized pattern search exactly as in the paper Appendix A2 (MATLAB patternsearch GPS,
  positive basis 2N, opportunistic polling, mesh expansion 2 / contraction 0.5), with bound constraints handled by
  projecting poll points onto the box.
* :func:`minimize_bounded` — first-order optimisation with an optax transformation (default Adam) in unconstrained
  variables ``z``, ``x = lo (hi/lo)^sigmoid(z)``, for objectives that also return a gradient (e.g. by the adjoint of
  the cycle solve).
* :func:`minimize_log_box` — projected quasi-Newton (optax L-BFGS direction) in ``z = log x`` with the box as
  an active set: the default for the foil design, where optima often sit on a bound.

The module knows nothing about bearings: variables are plain arrays, in whatever units (usually dimensionless) the
objective uses.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np
import optax

__all__ = [
    "Evaluation",
    "SearchResult",
    "pattern_search",
    "GradientEvaluation",
    "GradientResult",
    "minimize_bounded",
    "minimize_log_box",
    "to_unconstrained",
    "from_unconstrained",
    "from_unconstrained_derivative",
]

ArrayLike = Sequence[float] | np.ndarray
Callback = Callable[[int, np.ndarray, float], Any]


# ----------------------------------------------------------------------------------------------------------------
# results


class Evaluation(NamedTuple):
    """One objective evaluation of :func:`pattern_search`.

    ``x``: the point; ``f``: its value (``inf`` for a failed evaluation); ``iteration``: 0 for the start point, k for
    the polls of iteration k; ``accepted``: the point became the current iterate; ``failure``: ``None``, or why the
    evaluation failed (``"nan"``, ``"inf"``, or ``"<ExceptionType>: message"``).
    """

    x: np.ndarray
    f: float
    iteration: int
    accepted: bool
    failure: str | None = None


class _HistoryMixin:
    history: list

    @property
    def xs(self) -> np.ndarray:
        """All evaluated points, shape (n_evals, d), in evaluation order."""
        d = len(self.x)  # type: ignore[attr-defined]
        return np.array([e.x for e in self.history]).reshape(-1, d)

    @property
    def fs(self) -> np.ndarray:
        """All objective values (``inf`` where failed), shape (n_evals,)."""
        return np.array([e.f for e in self.history], dtype=float)

    @property
    def n_failed(self) -> int:
        """Number of failed evaluations."""
        return sum(e.failure is not None for e in self.history)


@dataclass
class SearchResult(_HistoryMixin):
    """Outcome of :func:`pattern_search`.

    ``x``, ``fun``: best point and value; ``n_evals``: objective evaluations (failed ones included,
    ``== len(history)``); ``n_iter``: poll iterations done; ``reason``: the stopping rule (see :func:`pattern_search`);
    ``mesh``: final mesh size; ``history``: every evaluation in order; ``trace``: best value at the start (index 0)
    and after each iteration (index k), length ``n_iter + 1``.
    """

    x: np.ndarray
    fun: float
    n_evals: int
    n_iter: int
    reason: str
    mesh: float
    history: list[Evaluation] = field(default_factory=list)
    trace: list[float] = field(default_factory=list)


class GradientEvaluation(NamedTuple):
    """One call of ``fun_and_grad`` in :func:`minimize_bounded`.

    ``x`` and ``z``: the point in physical and unconstrained variables; ``f``: value (``inf`` if failed); ``g``:
    gradient w.r.t. x (nan-filled if failed); ``iteration``: 0 for the start, k for the step of iteration k and its
    backtracks; ``accepted``: the point became the current iterate; ``failure``: ``None`` or the reason.
    """

    x: np.ndarray
    z: np.ndarray
    f: float
    g: np.ndarray
    iteration: int
    accepted: bool
    failure: str | None = None


@dataclass
class GradientResult(_HistoryMixin):
    """Outcome of :func:`minimize_bounded`.

    ``x``, ``fun``, ``grad``: best point seen, its value and gradient w.r.t. x; ``n_evals`` / ``n_grads``: function /
    gradient evaluations (each ``fun_and_grad`` call counts one of each, failed ones included); ``n_iter``: optimiser
    steps; ``reason``: the stopping rule (see :func:`minimize_bounded`); ``history``: every call in order; ``trace``:
    best value at the start (index 0) and after each iteration.
    """

    x: np.ndarray
    fun: float
    grad: np.ndarray
    n_evals: int
    n_grads: int
    n_iter: int
    reason: str
    history: list[GradientEvaluation] = field(default_factory=list)
    trace: list[float] = field(default_factory=list)


# ----------------------------------------------------------------------------------------------------------------
# input checks (all before the first evaluation)


def _vector(name: str, value: ArrayLike, d: int | None = None) -> np.ndarray:
    a = np.array(value, dtype=float).reshape(-1) if np.ndim(value) <= 1 else None
    if a is None:
        raise ValueError(f"{name} must be a 1-D array, got shape {np.shape(value)}")
    if a.size == 0:
        raise ValueError(f"{name} must have at least one entry")
    if d is not None and a.size != d:
        raise ValueError(f"{name} must have {d} entries (one per variable), got {a.size}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite, got {a}")
    return a


def _bounds(x0: ArrayLike, lo: ArrayLike, hi: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    x = _vector("x0", x0)
    lo_a = _vector("lo", lo, x.size)
    hi_a = _vector("hi", hi, x.size)
    for i in range(x.size):
        if not lo_a[i] < hi_a[i]:
            raise ValueError(f"lo[{i}] = {lo_a[i]:g} must be < hi[{i}] = {hi_a[i]:g}")
    return x, lo_a, hi_a


def _check_inside(x: np.ndarray, lo: np.ndarray, hi: np.ndarray, *, open_: bool) -> None:
    for i in range(x.size):
        bad = not (lo[i] < x[i] < hi[i]) if open_ else not (lo[i] <= x[i] <= hi[i])
        if bad:
            l_, r_ = ("(", ")") if open_ else ("[", "]")
            raise ValueError(f"x0[{i}] = {x[i]:g} outside its bounds {l_}lo, hi{r_} = {l_}{lo[i]:g}, {hi[i]:g}{r_}")


def _positive(name: str, value: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) \
            or not math.isfinite(value) or value <= 0:
        raise ValueError(f"{name} must be a finite number in (0, inf), got {value!r}")
    return float(value)


def _nonneg(name: str, value: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) \
            or math.isnan(value) or value < 0:
        raise ValueError(f"{name} must be a number in [0, inf], got {value!r}")
    return float(value)


def _count(name: str, value: int | None, minimum: int, *, optional: bool = False) -> int | None:
    if value is None and optional:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be an integer in [{minimum}, inf){' or None' if optional else ''}, "
                         f"got {value!r}")
    return int(value)


def _failure_of(f: float) -> str | None:
    if math.isnan(f):
        return "nan"
    if math.isinf(f):
        return "inf"
    return None


def _bar(progress: bool, total: int, desc: str):
    if not progress:
        return None
    import sys

    from tqdm.auto import tqdm

    return tqdm(total=total, desc=desc, unit="it", file=sys.stderr, dynamic_ncols=True)


# ----------------------------------------------------------------------------------------------------------------
# generalized pattern search (paper Appendix A2)


def pattern_search(
    fun: Callable[[np.ndarray], float],
    x0: ArrayLike,
    lo: ArrayLike,
    hi: ArrayLike,
    *,
    mesh0: float = 1.0,
    expansion: float = 2.0,
    contraction: float = 0.5,
    scale: ArrayLike | None = None,
    mesh_tol: float = 1e-6,
    max_iter: int = 300,
    max_evals: int | None = None,
    step_tol: float = 1e-6,
    f_tol: float = 1e-6,
    failures: tuple[type[Exception], ...] = (),
    callback: Callback | None = None,
    progress: bool = False,
) -> SearchResult:
    """Minimise ``fun`` over the box ``lo <= x <= hi`` by generalized pattern search (paper Appendix A2).

    The algorithm is MATLAB's ``patternsearch`` with ``PollMethod = "GPSPositiveBasis2N"``,
    ``UseCompletePoll = false`` (opportunistic), ``ScaleMesh = false`` and no search step:

    1. evaluate ``x0``; mesh size ``m = mesh0``;
    2. poll ``x + m s_1 e_1, ..., x + m s_d e_d, x - m s_1 e_1, ..., x - m s_d e_d`` in this order (``s = scale``);
       a poll point outside the box is projected onto it, and skipped (not evaluated) if the projection is ``x``;
    3. at the first poll point with a value strictly below ``f(x)`` stop polling, move there and set
       ``m *= expansion`` (successful poll); if none improves, stay and set ``m *= contraction``;
    4. repeat 2-3 until a stopping rule holds.

    Stopping rules, checked after each iteration in this order (``reason`` of the result):

    * ``"step_tol"`` (MATLAB StepTolerance): after a successful poll, the step length ``|x_k - x_{k-1}|`` and the
      new mesh size are both below ``step_tol``;
    * ``"f_tol"`` (FunctionTolerance): after a successful poll, ``|f_k - f_{k-1}| < f_tol`` and the mesh size is
      below ``step_tol``;
    * ``"mesh_tol"`` (MeshTolerance): mesh size below ``mesh_tol`` (the normal, converged end);
    * ``"max_iter"`` (MaxIterations): ``max_iter`` iterations done;
    * ``"max_evals"`` (MaxFunctionEvaluations): ``max_evals`` evaluations done; checked before every evaluation
      too, so the count never exceeds it (the iteration it cuts short still counts);
    * ``"callback"``: ``callback`` returned ``True``;
    * ``"interrupted"``: KeyboardInterrupt; the result holds everything evaluated before it.

    Args:
        fun: objective ``fun(x) -> float`` on a copy of the point (shape (d,)). A value of nan or +-inf, or an
            exception of a type in ``failures``, marks a failed evaluation: it counts, is recorded with value
            ``inf`` and is never an improvement. Other exceptions propagate.
        x0: start point, shape (d,), inside the closed box.
        lo, hi: bounds, shape (d,), ``lo < hi``, in the units of x.
        mesh0: initial mesh size, > 0 (units of x / scale).
        expansion: mesh factor after a successful poll, >= 1.
        contraction: mesh factor after an unsuccessful poll, in (0, 1).
        scale: per-variable pattern scale, > 0 (default ones: the paper's unit pattern).
        mesh_tol, max_iter, max_evals, step_tol, f_tol: stopping rules above (``max_evals=None``: unlimited).
        failures: exception types of ``fun`` that mean "failed evaluation".
        callback: ``callback(iteration, x, f)`` after every iteration with the current (best) point; returning
            ``True`` stops the search.
        progress: show a tqdm bar over iterations (on stderr).

    Returns:
        :class:`SearchResult`.
    """
    x, lo_a, hi_a = _bounds(x0, lo, hi)
    _check_inside(x, lo_a, hi_a, open_=False)
    d = x.size
    mesh = _positive("mesh0", mesh0)
    expansion = _positive("expansion", expansion)
    if expansion < 1.0:
        raise ValueError(f"expansion must be in [1, inf), got {expansion!r}")
    contraction = _positive("contraction", contraction)
    if contraction >= 1.0:
        raise ValueError(f"contraction must be in (0, 1), got {contraction!r}")
    s = np.ones(d) if scale is None else _vector("scale", scale, d)
    if np.any(s <= 0):
        raise ValueError(f"scale must be > 0 in every entry, got {s}")
    mesh_tol = _positive("mesh_tol", mesh_tol)
    max_iter = _count("max_iter", max_iter, 1)
    max_evals = _count("max_evals", max_evals, 1, optional=True)
    step_tol = _nonneg("step_tol", step_tol)
    f_tol = _nonneg("f_tol", f_tol)
    failures = tuple(failures)

    directions = np.concatenate([np.eye(d), -np.eye(d)]) * s  # GPS positive basis 2N, MATLAB's order
    history: list[Evaluation] = []
    trace: list[float] = []
    f = math.inf
    n_iter = 0
    reason = "interrupted"
    bar = _bar(progress, max_iter, "pattern search")

    def evaluate(p: np.ndarray, it: int) -> tuple[float, str | None]:
        try:
            val = float(fun(p.copy()))
            why = _failure_of(val)
        except failures as exc:  # type: ignore[misc]
            val, why = math.inf, f"{type(exc).__name__}: {exc}"
        if why is not None:
            val = math.inf
        history.append(Evaluation(p.copy(), val, it, False, why))
        return val, why

    def accept() -> None:
        history[-1] = history[-1]._replace(accepted=True)

    try:
        f, _ = evaluate(x, 0)
        accept()
        trace.append(f)
        if mesh < mesh_tol:
            reason = "mesh_tol"
        while mesh >= mesh_tol:
            n_iter += 1
            x_old, f_old = x, f
            success = cut_short = False
            for v in directions:
                p = np.clip(x + mesh * v, lo_a, hi_a)
                if np.array_equal(p, x):
                    continue  # projection fell back onto the iterate: MATLAB's zero step, not evaluated
                if max_evals is not None and len(history) >= max_evals:
                    cut_short = True
                    break
                fp, _ = evaluate(p, n_iter)
                if fp < f:
                    accept()
                    x, f, success = p, fp, True
                    break
            if not cut_short:
                mesh *= expansion if success else contraction
            trace.append(f)
            if bar is not None:
                bar.update(1)
                bar.set_postfix(f=f"{f:.6g}", mesh=f"{mesh:.3g}", evals=len(history))
            stop = bool(callback(n_iter, x.copy(), f)) if callback is not None else False
            if success and np.linalg.norm(x - x_old) < step_tol and mesh < step_tol:
                reason = "step_tol"
            elif success and abs(f - f_old) < f_tol and mesh < step_tol:
                reason = "f_tol"
            elif mesh < mesh_tol:
                reason = "mesh_tol"
            elif n_iter >= max_iter:
                reason = "max_iter"
            elif cut_short or (max_evals is not None and len(history) >= max_evals):
                reason = "max_evals"
            elif stop:
                reason = "callback"
            else:
                continue
            break
    except KeyboardInterrupt:
        reason = "interrupted"
    finally:
        if bar is not None:
            bar.close()
    if len(trace) < n_iter + 1:  # interrupted inside an iteration: it still counts, with the best so far
        trace.append(f)
    return SearchResult(x=x.copy(), fun=f, n_evals=len(history), n_iter=n_iter, reason=reason, mesh=mesh,
                        history=history, trace=trace)


# ----------------------------------------------------------------------------------------------------------------
# log-space sigmoid reparametrisation


def _log_bounds(lo: ArrayLike, hi: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    lo_a = _vector("lo", lo)
    hi_a = _vector("hi", hi, lo_a.size)
    for i in range(lo_a.size):
        if not lo_a[i] > 0:
            raise ValueError(f"lo[{i}] = {lo_a[i]:g} must be in (0, inf): the log-space map needs positive bounds")
        if not lo_a[i] < hi_a[i]:
            raise ValueError(f"lo[{i}] = {lo_a[i]:g} must be < hi[{i}] = {hi_a[i]:g}")
    return lo_a, hi_a


def _log_sigmoid(z: np.ndarray) -> np.ndarray:
    return -np.logaddexp(0.0, -z)  # log(1/(1+e^-z)) without overflow for large |z|


def to_unconstrained(x: ArrayLike, lo: ArrayLike, hi: ArrayLike) -> np.ndarray:
    """Unconstrained ``z`` of a point ``lo < x < hi``: the inverse of :func:`from_unconstrained`.

    ``z = logit(s)`` with ``s = log(x/lo) / log(hi/lo)`` in (0, 1). Requires ``0 < lo < hi`` (ValueError naming the
    bound otherwise); x on or outside a bound gives ``-inf``/``+inf``/nan.

    Args:
        x: point, shape (d,), same units as the bounds.
        lo, hi: bounds, shape (d,).
    """
    lo_a, hi_a = _log_bounds(lo, hi)
    x_a = np.asarray(x, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.log(x_a / lo_a) / np.log(hi_a / lo_a)
        return np.log(s) - np.log1p(-s)


def from_unconstrained(z: ArrayLike, lo: ArrayLike, hi: ArrayLike) -> np.ndarray:
    """Physical point of unconstrained ``z``: ``x = lo (hi/lo)^sigmoid(z)``, never outside [lo, hi].

    x is strictly inside unless ``sigmoid(z)`` rounds to 0 or 1 (``|z|`` above ~37).

    Uniform steps in z near 0 are uniform steps in log x, so variables spanning decades are treated alike.
    Requires ``0 < lo < hi`` (ValueError naming the bound otherwise).

    Args:
        z: unconstrained variables, shape (d,) (dimensionless).
        lo, hi: bounds, shape (d,).
    """
    lo_a, hi_a = _log_bounds(lo, hi)
    s = np.exp(_log_sigmoid(np.asarray(z, dtype=float)))
    # clip: where s rounds to 1, lo * exp(log(hi/lo)) can land an ulp above hi
    return np.clip(lo_a * np.exp(s * np.log(hi_a / lo_a)), lo_a, hi_a)


def from_unconstrained_derivative(z: ArrayLike, lo: ArrayLike, hi: ArrayLike) -> np.ndarray:
    """Diagonal Jacobian ``dx_i/dz_i`` of :func:`from_unconstrained` (the map is element-wise).

    With ``s = sigmoid(z)`` and ``x = lo exp(s log(hi/lo))``: ``dx/dz = x log(hi/lo) s (1 - s)``; the gradient of
    an objective in z is then ``df/dz = df/dx * dx/dz``.

    Args:
        z: unconstrained variables, shape (d,).
        lo, hi: bounds, shape (d,).
    """
    lo_a, hi_a = _log_bounds(lo, hi)
    z_a = np.asarray(z, dtype=float)
    x = from_unconstrained(z_a, lo_a, hi_a)
    s_1ms = np.exp(_log_sigmoid(z_a) + _log_sigmoid(-z_a))  # s (1 - s), exact where s ~ 1
    return x * np.log(hi_a / lo_a) * s_1ms


# ----------------------------------------------------------------------------------------------------------------
# gradient-based bounded minimisation


def minimize_bounded(
    fun_and_grad: Callable[[np.ndarray], tuple[float, np.ndarray]],
    x0: ArrayLike,
    lo: ArrayLike,
    hi: ArrayLike,
    *,
    optimizer: optax.GradientTransformation | None = None,
    learning_rate: float | optax.Schedule = 0.2,
    max_iter: int = 100,
    max_evals: int | None = None,
    f_rtol: float = 1e-6,
    f_atol: float = 0.0,
    patience: int = 5,
    g_tol: float = 1e-8,
    max_backtracks: int = 10,
    failures: tuple[type[Exception], ...] = (),
    callback: Callback | None = None,
    progress: bool = False,
) -> GradientResult:
    """Minimise a differentiable objective over the box ``lo < x < hi`` with an optax optimiser.

    The box is removed by the log-space sigmoid map ``x = lo (hi/lo)^sigmoid(z)`` (:func:`from_unconstrained`,
    needs ``0 < lo``); the optimiser steps in z with ``df/dz = df/dx * dx/dz``
    (:func:`from_unconstrained_derivative`). The best point seen is returned, not the last (Adam is not monotone).

    A failed evaluation (nan/inf value or gradient, or an exception of a type in ``failures``) is recorded and
    counted; the step is then halved back toward the last good z, up to ``max_backtracks`` times.

    Stopping rules (``reason`` of the result):

    * ``"f_rtol"``: over the last ``patience`` iterations the spread (max - min) of the iterate values is
      ``<= f_rtol * max|f| + f_atol`` (set ``f_atol`` when the minimum value is ~0);
    * ``"g_tol"``: gradient norm in z ``< g_tol`` (also checked at the start point);
    * ``"max_iter"``, ``"max_evals"``: limits reached (``max_evals`` is never exceeded);
    * ``"backtrack_failed"``: a step still failed after ``max_backtracks`` halvings;
    * ``"start_failed"``: ``x0`` itself failed (then ``fun = inf``);
    * ``"callback"``: ``callback`` returned ``True``;
    * ``"interrupted"``: KeyboardInterrupt; the result holds everything evaluated before it.

    Args:
        fun_and_grad: ``fun_and_grad(x) -> (f, g)``, value and gradient w.r.t. the physical x (shape (d,)).
            Other exceptions than ``failures`` propagate.
        x0: start point, shape (d,), strictly inside the box.
        lo, hi: bounds, shape (d,), ``0 < lo < hi``.
        optimizer: any ``optax.GradientTransformation`` acting on z (default ``optax.adam(learning_rate)``).
        learning_rate: step size in z (dimensionless) of the default Adam; ignored if ``optimizer`` is given.
        max_iter: optimiser steps, >= 1.
        max_evals: most ``fun_and_grad`` calls (None: unlimited), >= 1.
        f_rtol, f_atol, patience, g_tol: convergence tests above.
        max_backtracks: halvings after a failed evaluation, >= 0.
        failures: exception types of ``fun_and_grad`` that mean "failed evaluation".
        callback: ``callback(iteration, x, f)`` after every iteration with the current iterate; ``True`` stops.
        progress: show a tqdm bar over iterations (on stderr).

    Returns:
        :class:`GradientResult`.
    """
    x0_a = _vector("x0", x0)
    lo_a, hi_a = _log_bounds(lo, hi)
    if lo_a.size != x0_a.size:
        raise ValueError(f"lo and hi must have {x0_a.size} entries (one per variable), got {lo_a.size}")
    _check_inside(x0_a, lo_a, hi_a, open_=True)
    if optimizer is None:
        if not callable(learning_rate):
            _positive("learning_rate", learning_rate)
        optimizer = optax.adam(learning_rate)
    elif not isinstance(optimizer, optax.GradientTransformation):
        raise ValueError(f"optimizer must be an optax.GradientTransformation, got {type(optimizer).__name__}")
    max_iter = _count("max_iter", max_iter, 1)
    max_evals = _count("max_evals", max_evals, 1, optional=True)
    f_rtol = _nonneg("f_rtol", f_rtol)
    f_atol = _nonneg("f_atol", f_atol)
    patience = _count("patience", patience, 1)
    g_tol = _nonneg("g_tol", g_tol)
    max_backtracks = _count("max_backtracks", max_backtracks, 0)
    failures = tuple(failures)
    d = x0_a.size

    history: list[GradientEvaluation] = []
    trace: list[float] = []
    values: list[float] = []  # iterate values, for the f_rtol window
    best: tuple[np.ndarray, float, np.ndarray] = (x0_a.copy(), math.inf, np.full(d, np.nan))
    n_iter = 0
    reason = "interrupted"
    bar = _bar(progress, max_iter, "minimize")

    def evaluate(z: np.ndarray, it: int) -> tuple[float, np.ndarray, str | None]:
        nonlocal best
        x = from_unconstrained(z, lo_a, hi_a)
        if it == 0:
            x = x0_a.copy()  # the caller's x0 exactly, not its round trip through z
        try:
            val, g = fun_and_grad(x.copy())
            val = float(val)
            g = np.asarray(g, dtype=float).reshape(-1)
            if g.size != d:
                raise ValueError(f"fun_and_grad returned a gradient with {g.size} entries, expected {d}")
            why = _failure_of(val) or (None if np.all(np.isfinite(g)) else "non-finite gradient")
        except failures as exc:  # type: ignore[misc]
            val, g, why = math.inf, np.full(d, np.nan), f"{type(exc).__name__}: {exc}"
        if why is not None:
            val, g = math.inf, np.full(d, np.nan)
        history.append(GradientEvaluation(x, z.copy(), val, g, it, why is None, why))
        if why is None and val < best[1]:
            best = (x.copy(), val, g.copy())
        return val, g, why

    def out_of_evals() -> bool:
        return max_evals is not None and len(history) >= max_evals

    @jax.jit
    def step(g_z, state, z):
        updates, state = optimizer.update(g_z, state, z)
        return optax.apply_updates(z, updates), state

    try:
        z = to_unconstrained(x0_a, lo_a, hi_a)
        f, g, why = evaluate(z, 0)
        trace.append(best[1])
        if why is not None:
            reason = "start_failed"
        else:
            values.append(f)
            g_z = g * from_unconstrained_derivative(z, lo_a, hi_a)
            state = optimizer.init(jnp.asarray(z))
            reason = "g_tol" if np.linalg.norm(g_z) < g_tol else ""
            while not reason:
                if out_of_evals():
                    reason = "max_evals"
                    break
                n_iter += 1
                z_new, state = step(jnp.asarray(g_z), state, jnp.asarray(z))
                z_new = np.asarray(z_new, dtype=float)
                f_new, g_new, why = evaluate(z_new, n_iter)
                dz, k = z_new - z, 0
                while why is not None and k < max_backtracks and not out_of_evals():
                    k += 1
                    # halve back toward the last good z: failures usually lie beyond an edge (e.g. of stability)
                    z_new = z + 0.5 ** k * dz
                    f_new, g_new, why = evaluate(z_new, n_iter)
                trace.append(best[1])
                if bar is not None:
                    bar.update(1)
                    bar.set_postfix(f=f"{best[1]:.6g}", evals=len(history))
                if why is not None:
                    reason = "max_evals" if k < max_backtracks else "backtrack_failed"
                    break
                z, f, g = z_new, f_new, g_new
                values.append(f)
                g_z = g * from_unconstrained_derivative(z, lo_a, hi_a)
                stop = bool(callback(n_iter, history[-1].x.copy(), f)) if callback is not None else False
                window = values[-(patience + 1):]
                if len(window) == patience + 1 and \
                        max(window) - min(window) <= f_rtol * max(abs(v) for v in window) + f_atol:
                    reason = "f_rtol"
                elif np.linalg.norm(g_z) < g_tol:
                    reason = "g_tol"
                elif n_iter >= max_iter:
                    reason = "max_iter"
                elif out_of_evals():
                    reason = "max_evals"
                elif stop:
                    reason = "callback"
    except KeyboardInterrupt:
        reason = "interrupted"
    finally:
        if bar is not None:
            bar.close()
    if len(trace) < n_iter + 1:
        trace.append(best[1])
    n = len(history)
    return GradientResult(x=best[0], fun=best[1], grad=best[2], n_evals=n, n_grads=n, n_iter=n_iter,
                          reason=reason, history=history, trace=trace)


# ----------------------------------------------------------------------------------------------------------------
# projected quasi-Newton in log variables (optax L-BFGS direction)

def minimize_log_box(
    fun_and_grad: Callable[[np.ndarray], tuple[float, np.ndarray]],
    x0: ArrayLike,
    lo: ArrayLike,
    hi: ArrayLike,
    *,
    optimizer: optax.GradientTransformation | None = None,
    max_step: float = 1.0,
    max_iter: int = 100,
    max_evals: int | None = None,
    g_tol: float = 1e-7,
    z_tol: float = 1e-6,
    f_rtol: float = 0.0,
    max_backtracks: int = 8,
    failures: tuple[type[Exception], ...] = (),
    callback: Callback | None = None,
    progress: bool = False,
) -> GradientResult:
    """Minimise ``fun_and_grad`` over the box ``lo <= x <= hi`` (``lo > 0``) by a projected quasi-Newton method in
    ``z = log x``.

    Each iteration: gradient in z (``g_z = g_x * x``); components at a bound whose gradient pushes outward are
    frozen (the active set of the box); the optax transformation (default ``optax.scale_by_lbfgs()``) turns the
    free gradient into a direction (the first step, and any step where that direction is not a descent one,
    goes a full ``max_step`` along the steepest descent); the step is capped at ``max_step`` in the infinity norm (log units: the cap
    keeps each new point within the convergence basin of a warm-started inner solve), projected onto the box and
    accepted on the Armijo condition, halved otherwise (a failed evaluation counts as a rejection).  Reaching a
    bound costs no extra evaluations, and an optimum at a bound or a corner is recognised by the first-order
    (KKT) condition at once.

    Stopping rules (``reason``): ``"kkt"`` — infinity norm of the free gradient in z below ``g_tol * max(1, |f|)``;
    ``"z_tol"`` — accepted step below ``z_tol``; ``"f_rtol"`` (only with ``f_rtol > 0``; off by default) — an
    accepted step gained at most ``f_rtol * |f|``, which ends the crawl along the ridge of a kink of the objective
    where the gradient never vanishes; ``"max_iter"``, ``"max_evals"``, ``"backtrack_failed"``,
    ``"start_failed"``, ``"callback"``, ``"interrupted"`` as in :func:`minimize_bounded`.

    Every call of ``fun_and_grad`` counts as one evaluation and one gradient.
    """
    x0, lo_, hi_ = _bounds(x0, lo, hi)
    if np.any(lo_ <= 0):
        raise ValueError(f"lo must be > 0 for log variables, got {lo_.tolist()}")
    _check_inside(x0, lo_, hi_, open_=False)
    max_step = _positive("max_step", max_step)
    max_iter = _count("max_iter", max_iter, 1)
    max_evals = _count("max_evals", max_evals, 1, optional=True)
    f_rtol = _nonneg("f_rtol", f_rtol)
    zl, zh = np.log(lo_), np.log(hi_)
    opt = optimizer if optimizer is not None else optax.scale_by_lbfgs()
    hist: list[GradientEvaluation] = []
    trace: list[float] = []
    counters = {"n": 0}
    it = 0

    def to_x(z: np.ndarray) -> np.ndarray:
        # exp(log(hi)) can round an ulp past hi (exp(log(10)) = 10.000000000000002): the point on a bound must be
        # the bound itself, or the caller's own bound check refuses it
        return np.clip(np.exp(z), lo_, hi_)

    def evaluate(z: np.ndarray) -> tuple[float, np.ndarray | None, str | None]:
        x = to_x(z)
        counters["n"] += 1
        try:
            f, g = fun_and_grad(x)
            f, g = float(f), np.asarray(g, float) * x
        except failures as e:  # noqa: PERF203
            hist.append(GradientEvaluation(x, z, math.inf, np.full_like(z, np.nan), it, False, repr(e)))
            return math.inf, None, repr(e)
        fail = _failure_of(f) or (None if np.all(np.isfinite(g)) else "non-finite gradient")
        hist.append(GradientEvaluation(x, z, f if fail is None else math.inf, g, it, fail is None, fail))
        return (f, g, None) if fail is None else (math.inf, None, fail)

    def result(z, f, g, reason):
        return GradientResult(to_x(z), f, g if g is not None else np.full_like(z, np.nan), counters["n"],
                              counters["n"], it, reason, hist, trace)

    z = np.clip(np.log(x0), zl, zh)
    bar = _bar(progress, max_iter, "quasi-Newton")
    try:
        f, g, fail = evaluate(z)
        trace.append(f)
        if fail is not None:
            return result(z, f, g, "start_failed")
        state = opt.init(jnp.asarray(z))
        while True:
            eps = 1e-12 * (zh - zl)
            free = ~(((z <= zl + eps) & (g > 0)) | ((z >= zh - eps) & (g < 0)))
            gf = np.where(free, g, 0.0)
            if np.max(np.abs(gf)) <= g_tol * max(1.0, abs(f)):
                return result(z, f, g, "kkt")
            if it >= max_iter:
                return result(z, f, g, "max_iter")
            it += 1
            d, state = opt.update(jnp.asarray(gf), state, jnp.asarray(z))
            d = -np.where(free, np.asarray(d), 0.0)
            if it == 1 or float(np.dot(d, gf)) >= 0.0:
                # no curvature yet, or negative curvature (a concave stretch): a full trust step downhill; the
                # raw gradient would be a step of |g| log units, meaningless for a small objective
                d = -gf * (max_step / max(np.max(np.abs(gf)), 1e-300))
            d *= min(1.0, max_step / max(np.max(np.abs(d)), 1e-300))
            for _ in range(max_backtracks + 1):
                if max_evals is not None and counters["n"] >= max_evals:
                    return result(z, f, g, "max_evals")
                zn = np.clip(z + d, zl, zh)
                fn, gn, fail = evaluate(zn)
                if fail is None and fn <= f + 1e-4 * float(np.dot(gf, zn - z)):
                    break
                d *= 0.5
            else:
                return result(z, f, g, "backtrack_failed")
            step = float(np.max(np.abs(zn - z)))
            gain = f - fn
            z, f, g = zn, fn, gn
            trace.append(f)
            if bar is not None:
                bar.update(1)
                bar.set_postfix(f=f"{f:.6g}")
            if callback is not None and callback(it, to_x(z), f) is True:
                return result(z, f, g, "callback")
            if step < z_tol:
                return result(z, f, g, "z_tol")
            if f_rtol > 0 and gain <= f_rtol * abs(f):
                return result(z, f, g, "f_rtol")
    except KeyboardInterrupt:
        return result(z, f, g, "interrupted")
    finally:
        if bar is not None:
            bar.close()
