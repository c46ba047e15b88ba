r"""Projected BFGS in log variables that can be warm-started with the curvature of a previous, similar problem,
and that stops relative to the objective's scale (issue 15, item 3: the corrector of the optimised continuation).

:func:`minimize_warm` minimises ``f(x)`` over the box ``lo <= x <= hi`` (``lo > 0``) in ``z = log x``, like
:func:`gfbjax.design.optimizers.minimize_log_box`, but

* keeps a dense BFGS model ``B`` (shape (d, d), the Hessian of f in z) instead of optax's L-BFGS memory, so that
  the model of one speed can start the optimisation at the next (``hessian=``; returned in
  :attr:`WarmResult.hessian`): the first step is then a Newton step, not a blind trust step;
* stops when what is left to gain is small against ``|f|`` (rules ``"model"`` and ``"f_rtol"`` below), which
  accepts a well-predicted start point after its one evaluation;
* checks a stop by one long exploratory step (``explore``): a carried model can be too stiff for the problem at
  hand (max|mu| has plateaus that slope gently towards a better basin), and then says "nothing left" where a long
  step still gains.

The module knows nothing about bearings; it is meant for a few (2-4) variables (dense d x d algebra).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .optimizers import ArrayLike, Callback, GradientEvaluation, GradientResult, _bounds, _check_inside, _count, \
    _failure_of, _nonneg, _positive, minimize_log_box

__all__ = ["WarmResult", "minimize_warm", "minimize_cold", "model_decrease", "curvature_from_history"]


@dataclass
class WarmResult(GradientResult):
    """:class:`~gfbjax.design.optimizers.GradientResult` plus ``hessian``: the BFGS model of the Hessian of f in
    ``z = log x`` at the end (shape (d, d), symmetric positive definite; after a discarded model, the one of
    :func:`curvature_from_history` over this call's evaluations), or None if there is none.  Pass it as
    ``hessian=`` to the next, similar problem."""

    hessian: np.ndarray | None = None


def model_decrease(g: np.ndarray, B: np.ndarray | None, free: np.ndarray) -> float:
    """What a Newton step on the free variables would gain by the quadratic model, ``g_f^T B_ff^-1 g_f / 2``
    (units of f); ``inf`` when ``B`` is None or not positive definite on the free block, 0 with nothing free.

    Args:
        g: gradient in z, shape (d,).  B: model Hessian in z, shape (d, d), or None.  free: bool mask, shape (d,).
    """
    if not np.any(free):
        return 0.0
    if B is None:
        return math.inf
    Bf = B[np.ix_(free, free)]
    try:
        L = np.linalg.cholesky(Bf)
    except np.linalg.LinAlgError:
        return math.inf
    v = np.linalg.solve(L, g[free])
    return 0.5 * float(v @ v)


def _bfgs_update(B: np.ndarray | None, s: np.ndarray, y: np.ndarray) -> np.ndarray | None:
    sy = float(s @ y)
    if not sy > 1e-10 * float(np.linalg.norm(s) * np.linalg.norm(y)):
        return B  # no positive curvature along s (a kink of max|mu|, a concave stretch): keep the old model
    if B is None:  # first pair: the scaled identity of Nocedal & Wright (6.20), then the update
        B = np.eye(s.size) * (float(y @ y) / sy)
    Bs = B @ s
    return B + np.outer(y, y) / sy - np.outer(Bs, Bs) / float(s @ Bs)


def curvature_from_history(history: list[GradientEvaluation]) -> np.ndarray | None:
    """BFGS model of the Hessian in z (shape (d, d)) from another optimiser's evaluations in order (e.g.
    :attr:`~gfbjax.design.optimizers.GradientResult.history` of ``minimize_log_box``, whose L-BFGS memory is not
    a dense matrix): one update per pair of consecutive successful evaluations, rejected trial points included
    (each pair is a valid secant pair).  None when no pair shows positive curvature."""
    B, last = None, None
    for e in history:
        if e.failure is not None or not np.all(np.isfinite(e.g)):
            continue
        if last is not None and np.any(e.z != last.z):
            B = _bfgs_update(B, np.asarray(e.z - last.z, float), np.asarray(e.g - last.g, float))
        last = e
    return B


def minimize_warm(
    fun_and_grad: Callable[[np.ndarray], tuple[float, np.ndarray]],
    x0: ArrayLike,
    lo: ArrayLike,
    hi: ArrayLike,
    *,
    hessian: np.ndarray | None = None,
    f_rtol: float = 1e-4,
    f_atol: float = 0.0,
    g_tol: float = 1e-7,
    max_step: float = 1.0,
    max_iter: int = 100,
    max_evals: int | None = None,
    max_backtracks: int = 4,
    explore: float | None = 1.0,
    max_explore: int = 2,
    failures: tuple[type[Exception], ...] = (),
    callback: Callback | None = None,
) -> WarmResult:
    """Minimise ``fun_and_grad`` over the box ``lo <= x <= hi`` (``lo > 0``) by projected BFGS in ``z = log x``.

    Each iteration: gradient in z (``g_z = g_x * x``); variables on a bound whose gradient pushes outward are
    frozen (the active set); the direction is the Newton step of the model ``B`` on the free variables (steepest
    descent, a full ``max_step``, while there is no model or when the model step is not a descent direction),
    capped at ``max_step`` (infinity norm, log units), projected onto the box and accepted on the Armijo condition,
    halved otherwise (a failed evaluation counts as a rejection).  ``B`` is updated by BFGS with every accepted
    step that shows positive curvature.

    Stopping rules (``reason``):

    * ``"kkt"`` — infinity norm of the free gradient below ``g_tol * max(1, |f|)``;
    * ``"model"`` — the model's predicted gain :func:`model_decrease` is at most ``f_rtol * |f| + f_atol``
      (checked at the start too: a good start point and a good ``hessian`` cost one evaluation);
    * ``"f_rtol"`` — the last accepted step gained at most ``f_rtol * |f| + f_atol`` (e.g. on the ridge of a kink,
      where the gradient never vanishes);

    Before stopping by ``"model"`` or ``"f_rtol"`` (at most ``max_explore`` times per call) the step of length
    ``explore`` (log units, infinity norm) along the steepest descent of the free variables is evaluated; if it
    gains more than the tolerance, the model is discarded (it was wrong at that scale) and the iteration goes on
    from there.  One evaluation per stop; ``explore=None`` turns it off.
    * ``"max_iter"``, ``"max_evals"``, ``"backtrack_failed"`` (the best point is kept), ``"start_failed"``,
      ``"callback"``, ``"interrupted"`` as in :func:`gfbjax.design.optimizers.minimize_log_box`.

    Args:
        fun_and_grad: ``fun_and_grad(x) -> (f, g)``, value and gradient w.r.t. the physical x (shape (d,)).
        x0: start point, shape (d,), inside the closed box.
        lo, hi: bounds, shape (d,), ``0 < lo < hi``.
        hessian: model Hessian of f in z to start from, shape (d, d), symmetric positive definite (e.g.
            :attr:`WarmResult.hessian` of a previous, similar problem); None: none.
        f_rtol: relative gain below which the optimisation stops (rules ``"model"``, ``"f_rtol"``), >= 0.
        f_atol: absolute gain added to it (units of f; set it when the minimum value is ~0), >= 0.
        explore: length of the exploratory step, > 0, or None.  max_explore: most exploratory steps, >= 0.
        g_tol, max_step, max_iter, max_evals, max_backtracks, failures, callback: as in ``minimize_log_box``.

    Returns:
        :class:`WarmResult`; ``x`` is the best point evaluated.

    Raises:
        ValueError: bad bounds, start point, hessian or options (before any evaluation).
    """
    x0, lo_, hi_ = _bounds(x0, lo, hi)
    if np.any(lo_ <= 0):
        raise ValueError(f"lo must be > 0 for log variables, got {lo_.tolist()}")
    _check_inside(x0, lo_, hi_, open_=False)
    d = x0.size
    if hessian is not None:
        hessian = np.array(hessian, float)
        if hessian.shape != (d, d) or not np.all(np.isfinite(hessian)):
            raise ValueError(f"hessian must be a finite ({d}, {d}) array, got shape {hessian.shape}")
        hessian = 0.5 * (hessian + hessian.T)
    f_rtol, f_atol, g_tol = _nonneg("f_rtol", f_rtol), _nonneg("f_atol", f_atol), _nonneg("g_tol", g_tol)
    max_step = _positive("max_step", max_step)
    max_iter = _count("max_iter", max_iter, 1)
    max_evals = _count("max_evals", max_evals, 1, optional=True)
    max_backtracks = _count("max_backtracks", max_backtracks, 0)
    explore = None if explore is None else _positive("explore", explore)
    max_explore = _count("max_explore", max_explore, 0)
    zl, zh = np.log(lo_), np.log(hi_)
    eps = 1e-12 * (zh - zl)
    hist: list[GradientEvaluation] = []
    trace: list[float] = []
    B = hessian
    it = 0
    explored = 0
    best = {"z": None, "f": math.inf, "g": None}

    def evaluate(z: np.ndarray) -> tuple[float, np.ndarray | None]:
        # exp(log(hi)) may round an ulp past hi: clip, so that a point on a bound is the bound itself
        x = np.clip(np.exp(z), lo_, hi_)
        try:
            f, g = fun_and_grad(x.copy())
            f, g = float(f), np.asarray(g, float).reshape(-1) * x
            fail = _failure_of(f) or (None if g.size == d and np.all(np.isfinite(g)) else "bad gradient")
        except failures as e:  # noqa: PERF203
            f, g, fail = math.inf, np.full(d, np.nan), repr(e)
        hist.append(GradientEvaluation(x, z.copy(), f if fail is None else math.inf, g, it, fail is None, fail))
        if fail is not None:
            return math.inf, None
        if f < best["f"]:
            best.update(z=z.copy(), f=f, g=g.copy())
        return f, g

    def result(reason: str) -> WarmResult:
        z = best["z"] if best["z"] is not None else np.clip(np.log(x0), zl, zh)
        g = best["g"] if best["g"] is not None else np.full(d, np.nan)
        return WarmResult(np.clip(np.exp(z), lo_, hi_), best["f"], g / np.exp(z), len(hist), len(hist), it,
                          reason, hist, trace, B if B is not None else curvature_from_history(hist))

    z = np.clip(np.log(x0), zl, zh)
    try:
        f, g = evaluate(z)
        trace.append(f)
        if g is None:
            return result("start_failed")
        stop = None
        while True:
            free = ~(((z <= zl + eps) & (g > 0)) | ((z >= zh - eps) & (g < 0)))
            gf = np.where(free, g, 0.0)
            if np.max(np.abs(gf)) <= g_tol * max(1.0, abs(f)):
                return result("kkt")
            if stop is None and model_decrease(g, B, free) <= f_rtol * abs(f) + f_atol:
                stop = "model"
            if stop is not None:
                if explore is None or explored >= max_explore or \
                        (max_evals is not None and len(hist) >= max_evals):
                    return result(stop)
                explored += 1
                zp = np.clip(z - gf * (explore / np.max(np.abs(gf))), zl, zh)
                fp, gp = evaluate(zp)
                if gp is None or not f - fp > f_rtol * abs(f) + f_atol:
                    return result(stop)
                B, stop = None, None  # the model said "nothing left" and a long step gained: forget it
                z, f, g = zp, fp, gp
                trace.append(f)
                continue
            if it >= max_iter:
                return result("max_iter")
            it += 1
            dz = np.zeros(d)
            if B is not None and math.isfinite(model_decrease(g, B, free)):
                dz[free] = -np.linalg.solve(B[np.ix_(free, free)], g[free])
            if not float(dz @ gf) < 0.0:
                dz = -gf * (max_step / max(np.max(np.abs(gf)), 1e-300))
            dz *= min(1.0, max_step / max(np.max(np.abs(dz)), 1e-300))
            for _ in range(max_backtracks + 1):
                if max_evals is not None and len(hist) >= max_evals:
                    return result("max_evals")
                zn = np.clip(z + dz, zl, zh)
                fn, gn = evaluate(zn)
                if gn is not None and fn <= f + 1e-4 * float(gf @ (zn - z)):
                    break
                dz *= 0.5
            else:
                return result("backtrack_failed")
            B = _bfgs_update(B, zn - z, gn - g)
            gain = f - fn
            z, f, g = zn, fn, gn
            trace.append(f)
            if callback is not None and callback(it, np.clip(np.exp(z), lo_, hi_), f) is True:
                return result("callback")
            if gain <= f_rtol * abs(f) + f_atol:
                stop = "f_rtol"
    except KeyboardInterrupt:
        return result("interrupted")


def minimize_cold(
    fun_and_grad: Callable[[np.ndarray], tuple[float, np.ndarray]],
    x0: ArrayLike,
    lo: ArrayLike,
    hi: ArrayLike,
    *,
    f_rtol: float = 1e-4,
    max_step: float = 1.0,
    max_iter: int = 100,
    max_evals: int | None = None,
    failures: tuple[type[Exception], ...] = (),
    callback: Callback | None = None,
    **warm_options,
) -> WarmResult:
    """Minimise without a curvature model to start from: first
    :func:`~gfbjax.design.optimizers.minimize_log_box` (L-BFGS; its long early steps explore, and max|mu| can
    have several local minima far apart) until an accepted step gains at most ``f_rtol * |f|``, then, if it
    stopped for that reason, :func:`minimize_warm` from that point with the curvature of those evaluations
    (:func:`curvature_from_history`), which checks the stop by its exploratory step (a single short L-BFGS step
    can gain little while the gradient still promises much).  Any other stop of the first phase is final (e.g.
    ``"backtrack_failed"`` on the kink of max|mu| between two multipliers: the line search has already halved
    the step 8 times).

    The point where the first phase ended is not evaluated again.  ``warm_options`` go to
    :func:`minimize_warm` (e.g. ``f_atol``, ``explore``, ``max_backtracks``); ``max_evals`` bounds both phases
    together.  Returns a :class:`WarmResult` over both phases (history, counts; ``reason`` is
    ``"<first phase>+<second phase>"``, or the first phase's alone when there is no second one).
    """
    memo: dict[tuple[float, ...], tuple[float, np.ndarray]] = {}

    def once(x: np.ndarray) -> tuple[float, np.ndarray]:
        key = tuple(float(v) for v in x)
        if key not in memo:
            memo.clear()  # only the last point can come back (the start of the second phase)
            memo[key] = fun_and_grad(x)
        return memo[key]

    first = minimize_log_box(once, x0, lo, hi, f_rtol=f_rtol, max_step=max_step, max_iter=max_iter,
                             max_evals=max_evals, failures=failures, callback=callback)
    left = None if max_evals is None else max_evals - first.n_evals + 1  # + 1: the repeated start is free
    if first.reason != "f_rtol" or (left is not None and left < 2):
        return WarmResult(first.x, first.fun, first.grad, first.n_evals, first.n_grads, first.n_iter,
                          first.reason, first.history, first.trace, curvature_from_history(first.history))
    second = minimize_warm(once, first.x, lo, hi, hessian=curvature_from_history(first.history), f_rtol=f_rtol,
                           max_step=max_step, max_iter=max_iter, max_evals=left, failures=failures,
                           callback=callback, **warm_options)
    history = first.history + second.history[1:]
    best = second if second.fun <= first.fun else first
    grad = second.grad if best is second else first.grad / first.x  # minimize_log_box reports it in z
    return WarmResult(best.x, best.fun, grad, len(history), len(history), first.n_iter + second.n_iter,
                      f"{first.reason}+{second.reason}", history, first.trace + second.trace[1:], second.hessian)
