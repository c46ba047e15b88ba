r"""Foil optimisation at one speed and the optimised continuation in speed (paper Sect. 3.3 steps a-f, App. A2).

Objectives (:mod:`gfbjax.design.evaluate`): ``"W_cb"`` (OBJ1, maximise the gas-film dissipation per cycle; the paper's
pattern search minimises ``1/W_cb``) and ``"max_mu"`` (OBJ2, minimise the largest non-trivial Floquet multiplier
modulus).  Methods:

* ``"pattern"`` — the paper's generalized pattern search (:func:`gfbjax.design.optimizers.pattern_search`, Appendix A2: mesh
  1, x2 after a successful poll, x0.5 after a failed one, bounds of :data:`FOIL_BOUNDS`, mesh tolerance 1e-6, at
  most 300 iterations) on the raw variables (alpha_f, eta);
* ``"gradient"`` — projected quasi-Newton in log-variables with optax's L-BFGS direction
  (:func:`gfbjax.design.optimizers.minimize_log_box`) and the implicit gradients of :class:`~gfbjax.design.evaluate.FoilDesign`;
* ``"adam"`` — optax Adam on sigmoid-bounded log-variables (:func:`gfbjax.design.optimizers.minimize_bounded`): slower to
  converge, above all when the optimum is on a bound (kept for comparison).

Every cycle is warm-started from the previous one (step c).  Both methods count limit-cycle solves.
:func:`optimized_continuation` marches in speed (steps e-f): optimise at each speed from the previous optimum and
cycle, step the speed, and stop where the optimised cycle is unstable (no admissible foil keeps it stable) or no
cycle converges.  With ``predict`` (the default for the gradient method; issue 15, item 3) each speed starts from
the optimum and cycle extrapolated from the last optima (:mod:`gfbjax.design.predictor`) and is corrected by a
projected BFGS that carries its curvature model from speed to speed and stops relative to the objective's scale
(:func:`gfbjax.design.quasi_newton.minimize_warm`); the pattern method stays the paper's baseline.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..cont import LinearSolver, Outcome
from .evaluate import FOIL_BOUNDS, MULTIPLIER_TOL, CycleEvaluation, CycleNotConverged, FoilDesign, check_foil
from .optimizers import minimize_bounded, minimize_log_box, pattern_search
from .predictor import OptimumTrail
from .quasi_newton import minimize_cold, minimize_warm
from .. import limits
from ..params import ParameterError, Params

__all__ = ["OBJECTIVES", "METHODS", "SpeedOptimum", "Schedule", "optimize_at_speed", "optimized_continuation"]

OBJECTIVES = ("W_cb", "max_mu")
METHODS = ("gradient", "adam", "pattern")
#: Relative gain below which the warm (predictor) optimisation stops: 50x below the 0.5% within which the
#: schedule must match the pattern search's optima (issue 15, item 3).
WARM_F_RTOL = 1e-4
LO = np.array([FOIL_BOUNDS["alpha_f"][0], FOIL_BOUNDS["eta"][0]])
HI = np.array([FOIL_BOUNDS["alpha_f"][1], FOIL_BOUNDS["eta"][1]])


def _check(objective: str, method: str) -> None:
    if objective not in OBJECTIVES:
        raise ParameterError(f"objective = {objective!r} is not one of {OBJECTIVES}")
    if method not in METHODS:
        raise ParameterError(f"method = {method!r} is not one of {METHODS}")


def objective_value(ev: CycleEvaluation, objective: str) -> float:
    """The objective in its physical form: W_cb [p0 R L c] (to maximise) or max|mu| (to minimise)."""
    return ev.W_cb if objective == "W_cb" else ev.max_mu


@dataclass
class SpeedOptimum:
    """Result of one optimisation at speed ``omega``: the best foil, its cycle, the counts and the history
    (one row per evaluation: alpha_f, eta, objective value in physical form, seconds since the start);
    ``hessian``: the warm optimiser's final curvature model in (log alpha_f, log eta), shape (2, 2), or None."""

    omega: float
    objective: str
    method: str
    alpha_f: float
    eta: float
    value: float
    evaluation: CycleEvaluation
    n_solves: int
    n_gradients: int
    seconds: float
    reason: str
    history: np.ndarray = field(repr=False, default=None)
    hessian: np.ndarray | None = field(repr=False, default=None)


def optimize_at_speed(design: FoilDesign, objective: str = "W_cb", method: str = "gradient",
                      x0: tuple[float, float] | None = None, *, progress: bool = False, warm: bool = False,
                      hessian: np.ndarray | None = None, **options: Any) -> SpeedOptimum:
    """Optimise (alpha_f, eta) at the design's current speed from ``x0`` (default: the design's params).

    ``options`` go to :func:`gfbjax.design.optimizers.pattern_search`,
    :func:`~gfbjax.design.optimizers.minimize_log_box` or :func:`~gfbjax.design.optimizers.minimize_bounded`.  ``warm=True`` (gradient method only) stops relative
    to the objective's scale (``f_rtol``, default :data:`WARM_F_RTOL`) and returns the final curvature model in
    :attr:`SpeedOptimum.hessian`: with a ``hessian`` (shape (2, 2) in log variables, e.g. the previous speed's)
    it runs :func:`gfbjax.design.quasi_newton.minimize_warm` from it; without one (a cold start, where the
    objective may have several local minima far apart) :func:`gfbjax.design.quasi_newton.minimize_cold`
    (``minimize_log_box``, whose long L-BFGS steps explore, then ``minimize_warm``); ``progress`` is ignored.
    Raises :class:`CycleNotConverged` when no cycle converged, ParameterError for a bad objective or method."""
    _check(objective, method)
    if warm and method != "gradient":
        raise ParameterError(f"warm = True needs method = 'gradient', got {method!r}")
    p = design.params
    x0 = np.array(check_foil(*(x0 if x0 is not None else (p.alpha_f, p.eta))), float)
    n0, g0 = design.n_solves, design.n_gradients
    rows: list[tuple[float, float, float]] = []
    best: dict[str, Any] = {}
    sign = -1.0 if objective == "W_cb" else 1.0  # minimise -W_cb or max|mu|

    def keep(ev: CycleEvaluation) -> None:
        v = objective_value(ev, objective)
        rows.append((ev.alpha_f, ev.eta, v, time.perf_counter() - t0))
        if not best or sign * v < sign * best["value"]:
            best.update(value=v, ev=ev)

    t0 = time.perf_counter()
    if method == "pattern":
        def fun(x: np.ndarray) -> float:
            ev = design.evaluate(float(x[0]), float(x[1]))
            keep(ev)
            if objective == "W_cb":  # the paper's OBJ = 1/W_cb; a non-dissipating film is never an improvement
                return 1.0 / ev.W_cb if ev.W_cb > 0 else float("inf")
            return ev.max_mu

        opts = dict(mesh0=1.0, mesh_tol=1e-6, max_iter=300)
        opts.update(options)
        res = pattern_search(fun, np.clip(x0, LO, HI), LO, HI, failures=(CycleNotConverged,), progress=progress,
                             **opts)
    else:
        def fun_and_grad(x: np.ndarray) -> tuple[float, np.ndarray]:
            ev = design.evaluate(float(x[0]), float(x[1]), gradient=True)
            keep(ev)
            if objective == "W_cb":
                return -ev.W_cb, -np.asarray(ev.grad_W_cb)
            return ev.max_mu, np.asarray(ev.grad_max_mu)

        if warm:
            options = {"f_rtol": WARM_F_RTOL, **options}
            solver = minimize_warm if hessian is not None else minimize_cold
            extra = {"hessian": hessian} if hessian is not None else {}
            res = solver(fun_and_grad, np.clip(x0, LO, HI), LO, HI, failures=(CycleNotConverged,), **extra,
                         **options)
        elif method == "gradient":
            res = minimize_log_box(fun_and_grad, np.clip(x0, LO, HI), LO, HI, failures=(CycleNotConverged,),
                                   progress=progress, **options)
        else:
            res = minimize_bounded(fun_and_grad, np.clip(x0, LO * 1.0001, HI * 0.9999), LO, HI,
                                   failures=(CycleNotConverged,), progress=progress, **options)
    if not best:
        raise CycleNotConverged(f"no cycle converged during the optimisation at Omega_bar = {design.omega}")
    ev = best["ev"]
    design.orbit = ev.orbit  # continue from the optimum's cycle
    return SpeedOptimum(design.omega, objective, method, ev.alpha_f, ev.eta, best["value"], ev,
                        design.n_solves - n0, design.n_gradients - g0, time.perf_counter() - t0, res.reason,
                        np.array(rows), res.hessian if warm else None)


@dataclass
class Schedule:
    """Optimised foil schedule along the speed (paper Figs. 16-19): per speed the optimum (alpha_f, eta), the
    objective, W_cb, max|mu|, stability, the journal's max/min over the cycle and the multipliers; ``outcome``
    says why the march ended (``REACHED_END``, ``UNSTABLE``: an optimised cycle is unstable, ``NO_SOLUTION``: no
    cycle converged, ``INTERRUPTED``) and ``message`` gives the details; ``bifurcation_free_to`` is the last
    speed with a stable optimised cycle.  Per speed also the cycle solves spent there (``n_solves_per_speed``,
    failed and fallback solves included), the optimiser's stopping rule (``stop_reasons``) and the optimum's
    :attr:`~.evaluate.CycleEvaluation.multiplier_error` (``multiplier_error``; ``max_mu_resolved`` says where it
    is at most 1e-3: elsewhere, at low speed on N = 16, max|mu| is not the cycle's)."""

    objective: str
    method: str
    omega: list[float] = field(default_factory=list)
    alpha_f: list[float] = field(default_factory=list)
    eta: list[float] = field(default_factory=list)
    W_cb: list[float] = field(default_factory=list)
    max_mu: list[float] = field(default_factory=list)
    stable: list[bool] = field(default_factory=list)
    journal_max: list[np.ndarray] = field(default_factory=list)
    journal_min: list[np.ndarray] = field(default_factory=list)
    multipliers: list[np.ndarray] = field(default_factory=list)
    n_solves_per_speed: list[int] = field(default_factory=list)
    stop_reasons: list[str] = field(default_factory=list)
    multiplier_error: list[float] = field(default_factory=list)
    n_solves: int = 0
    n_gradients: int = 0
    seconds: float = 0.0
    outcome: Outcome = Outcome.INTERRUPTED
    message: str = ""

    @property
    def max_mu_resolved(self) -> list[bool]:
        """Per speed: the mesh resolves max|mu| (multiplier_error at most 1e-3, or not estimated)."""
        return [not e > MULTIPLIER_TOL for e in self.multiplier_error]

    @property
    def bifurcation_free_to(self) -> float | None:
        last = None
        for w, s in zip(self.omega, self.stable):
            if not s:
                break
            last = w
        return last

    def to_dict(self) -> dict[str, Any]:
        return {"objective": self.objective, "method": self.method, "Omega_bar": self.omega,
                "alpha_f": self.alpha_f, "eta": self.eta, "W_cb": self.W_cb, "max_mu": self.max_mu,
                "stable": self.stable, "journal_max": [a.tolist() for a in self.journal_max],
                "journal_min": [a.tolist() for a in self.journal_min],
                "multipliers_re": [np.real(a).tolist() for a in self.multipliers],
                "multipliers_im": [np.imag(a).tolist() for a in self.multipliers],
                "n_solves_per_speed": self.n_solves_per_speed, "stop_reasons": self.stop_reasons,
                "multiplier_error": self.multiplier_error, "max_mu_resolved": self.max_mu_resolved,
                "n_solves": self.n_solves, "n_gradients": self.n_gradients, "seconds": self.seconds,
                "outcome": str(self.outcome), "message": self.message,
                "bifurcation_free_to": self.bifurcation_free_to}


def optimized_continuation(params: Params, omega_start: float, omega_end: float, d_omega: float = 0.025, *,
                           objective: str = "max_mu", method: str = "gradient", x0: tuple[float, float] | None = None,
                           m: int = 4, N: int = 16, linear_solver: LinearSolver | None = None, progress: bool = False,
                           callback: Callable[[SpeedOptimum], Any] | None = None, predict: bool | None = None,
                           predict_order: int = 1, **options: Any) -> Schedule:
    """March from ``omega_start`` to ``omega_end`` in steps ``d_omega`` (Omega_bar), optimising the foil at each
    speed from the previous optimum and cycle (paper Sect. 3.3 steps a-f).  Ends at ``omega_end``, at the first
    speed whose optimised cycle is unstable (recorded), or where no cycle converges; never loses the finished
    speeds (also on KeyboardInterrupt).  The first speed's cycle comes from
    :func:`gfbjax.analyses.cycles.unbalance_response_start` (a ramp in the unbalance when the linear response would
    close the film); when no cycle converges from the last speed's optimum, the speed is approached again in
    halved steps at the last optimum's foil before the march gives up.

    ``predict`` (None: on for ``method="gradient"``, off otherwise; True needs the gradient method): start each
    speed from the optimum and cycle extrapolated from the last optima by a polynomial of degree up to
    ``predict_order`` (:class:`gfbjax.design.predictor.OptimumTrail`; a variable on a bound stays there; the
    secant, order 1, is the default: measured more robust than order 2 where the optimum jumps between the
    kinks and local minima of max|mu|, benchmarks/design_cost.py) and
    correct with :func:`gfbjax.design.quasi_newton.minimize_warm`, whose curvature model goes from speed to speed
    (``options`` then go to ``minimize_warm``, e.g. ``f_rtol``).  If no cycle converges at the predicted foil, the
    speed is tried again from the last optimum and its cycle."""
    _check(objective, method)
    if predict is None:
        predict = method == "gradient"
    if predict and method != "gradient":
        raise ParameterError(f"predict = True needs method = 'gradient', got {method!r}")
    if isinstance(predict_order, bool) or not isinstance(predict_order, int) or predict_order < 0:
        raise ParameterError(f"predict_order must be an integer >= 0, got {predict_order!r}")
    d_omega = limits.SPEED_STEP.check(d_omega)
    omega_start = limits.SPEED.check(omega_start, "omega_start")
    omega_end = limits.SPEED.check(omega_end, "omega_end")
    if not omega_start < omega_end:
        raise ParameterError(f"omega_end = {omega_end:g} must be above omega_start = {omega_start:g} (the march "
                             "goes up in speed)")
    design = FoilDesign(params, omega_start, m=m, N=N, linear_solver=linear_solver)
    sched = Schedule(objective, method)
    x = x0
    trail = OptimumTrail(np.log(LO), np.log(HI), order=predict_order) if predict else None
    warm = dict(warm=True, hessian=None) if predict else {}
    speeds = np.arange(omega_start, omega_end + 1e-12, d_omega)
    bar = None
    if progress:
        from tqdm.auto import tqdm
        bar = tqdm(total=len(speeds), desc=f"optimised continuation ({objective})")
    t0 = time.perf_counter()
    try:
        for w in speeds:
            w_prev, orbit_prev = design.omega, design.orbit
            n_before = design.n_solves
            opt = None
            if trail is not None and trail.omegas:
                # predicted foil and cycle; when its cycle does not converge, fall back on the plain warm start
                x_pred, orbit_pred = trail.predict(float(w))
                design.set_speed(float(w), orbit_pred)
                try:
                    opt = optimize_at_speed(design, objective, method, tuple(x_pred), **warm, **options)
                except CycleNotConverged:
                    opt = None
            if opt is None:
                design.set_speed(float(w), orbit_prev)  # step (e): the last optimum's cycle, period 2 pi / Omega
                try:
                    opt = optimize_at_speed(design, objective, method, x, **warm, **options)
                except CycleNotConverged as e:
                    # the last cycle was too far from this speed's (a strongly nonlinear cycle, a large unbalance):
                    # walk to this speed in smaller steps at the last optimum's foil, then optimise again
                    try:
                        if not sched.omega:
                            raise
                        design.set_speed(w_prev, orbit_prev)
                        _approach_speed(design, float(w), x if x is not None else (params.alpha_f, params.eta))
                        opt = optimize_at_speed(design, objective, method, x, **warm, **options)
                    except CycleNotConverged:
                        sched.outcome, sched.message = Outcome.NO_SOLUTION, f"no cycle at Omega_bar = {w:.4f}: {e}"
                        break
            ev = opt.evaluation
            x = (opt.alpha_f, opt.eta)
            if trail is not None:
                trail.add(float(w), np.array(x), ev.orbit, opt.hessian)
                warm["hessian"] = trail.hessian
            lay_idx = _journal_columns(params)
            U = np.asarray(ev.orbit.nodes())[..., lay_idx]
            sched.omega.append(float(w))
            sched.alpha_f.append(opt.alpha_f)
            sched.eta.append(opt.eta)
            sched.W_cb.append(ev.W_cb)
            sched.max_mu.append(ev.max_mu)
            sched.stable.append(ev.stable)
            sched.journal_max.append(U.max(axis=(0, 1)))
            sched.journal_min.append(U.min(axis=(0, 1)))
            sched.multipliers.append(np.asarray(ev.multipliers))
            sched.n_solves_per_speed.append(design.n_solves - n_before)
            sched.stop_reasons.append(opt.reason)
            sched.multiplier_error.append(float(ev.multiplier_error))
            if bar is not None:
                bar.update(1)
                bar.set_postfix(alpha_f=f"{opt.alpha_f:.3g}", eta=f"{opt.eta:.3g}", max_mu=f"{ev.max_mu:.4f}")
            if callback is not None:
                callback(opt)
            if not ev.stable:
                sched.outcome = Outcome.UNSTABLE
                sched.message = f"the optimised cycle is unstable at Omega_bar = {w:.4f} (max|mu| = {ev.max_mu:.4f})"
                break
        else:
            sched.outcome, sched.message = Outcome.REACHED_END, f"reached omega_end = {omega_end}"
    except KeyboardInterrupt:
        sched.outcome, sched.message = Outcome.INTERRUPTED, "interrupted; the finished speeds are kept"
    finally:
        if bar is not None:
            bar.close()
    sched.n_solves, sched.n_gradients = design.n_solves, design.n_gradients
    sched.seconds = time.perf_counter() - t0
    return sched


def _approach_speed(design: FoilDesign, omega: float, foil: tuple[float, float], min_step: float = 1e-3) -> None:
    """Move ``design`` from its converged cycle to a converged cycle at ``omega`` at the foil ``foil``, halving the
    speed step after every failed solve (natural continuation in Omega_bar).  Raises :class:`CycleNotConverged`
    when a step below ``min_step`` fails."""
    alpha_f, eta = float(foil[0]), float(foil[1])
    reached, targets = design.omega, [float(omega)]
    while targets:
        w = targets[-1]
        design.set_speed(w)
        try:
            design.evaluate(alpha_f, eta)
        except CycleNotConverged:
            if abs(w - reached) < min_step:
                raise
            design.set_speed(reached)
            targets.append(0.5 * (reached + w))
            continue
        reached = targets.pop()


def _journal_columns(params: Params) -> list[int]:
    from ..analyses.cycles import rotor_components

    return rotor_components(params)[:2]
