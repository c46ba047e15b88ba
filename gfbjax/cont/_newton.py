r"""The one Newton corrector of gfbjax: a state machine stepped either inside a compiled loop or from Python.

Every nonlinear solve of the package (collocation cycles on both linear-solver backends, equilibria and their
continuation, static equilibria of the bearing, the plain bearing, the batched design maps) runs this iteration.
The caller supplies one function, ``linearise(x) -> (rnorm, dx, aux)``: the residual's max-norm at ``x``, the full
Newton step ``dx = -J(x)^{-1} F(x)`` (same pytree structure as ``x``, zero where ``x`` holds fixed data such as a
mesh) and any by-product of the factorisation (a tangent, an LU) that the caller wants at the solution.

Iteration (one call of ``linearise`` per iteration; after a small step one more call checks the residual)::

    evaluate rnorm, dx, aux at x
    if the previous step was small:   converged when rnorm <= max(tol, 10 * previous rnorm)
                                       (aux is then the by-product at the returned x)
    if rnorm or |dx| is not finite:   NONFINITE       (x is the last finite iterate)
    if |dx| > divergence * min|dx|:   DIVERGED        (after two steps at least)
    if max_iter steps were taken:     MAX_ITERATIONS
    t = damping(x, dx, aux)           (1 by default, and 1 for a step already small; 0: no acceptable
                                       step, NONFINITE)
    x <- x + t dx;  small step when t == 1 and |dx| <= atol_step + rtol_step * scale(x)

With ``verify_residual=False`` a small full step converges at once (no extra evaluation): for solvers whose
residual cannot stall, such as the static bearing equilibria.

The same :func:`_advance` decides every transition for both drivers: :func:`solve` (``lax.while_loop``; pure,
jit-compiled, ``jax.vmap`` batches it over parameter sets) and :func:`solve_host` (a Python loop, for linear
solvers that run on the host such as SuperLU; a :class:`LinearSolveError` raised by ``linearise`` ends it with
``LINEAR_SOLVE_FAILED``, any other exception propagates).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._checks import check_flag, check_range, store
from ._results import Outcome

__all__ = ["NewtonSettings", "NewtonSolution", "LinearSolveError", "solve", "solve_host", "with_finite_tangent"]

_RUNNING = Outcome.RUNNING.code


class LinearSolveError(RuntimeError):
    """A linear solve on the host failed (a singular block, a Krylov breakdown); Newton reports
    ``Outcome.LINEAR_SOLVE_FAILED``."""


@dataclass(frozen=True)
class NewtonSettings:
    """Tolerances of the Newton corrector (checked at construction).

    tol: residual max-norm accepted after a small step (the residual check, see the module docstring; inf: the
    check only evaluates the residual at the returned point, for reporting).
    atol_step, rtol_step: a full step is small when ``|dx|_inf <= atol_step + rtol_step * scale(x)``.
    max_iter: most Newton steps. divergence: a step larger than this factor times the smallest step so far ends
    the iteration (``DIVERGED``). verify_residual: check the residual after a small step (one more evaluation).
    """

    tol: float = 1e-10
    atol_step: float = 1e-10
    rtol_step: float = 1e-10
    max_iter: int = 12
    divergence: float = 1e3
    verify_residual: bool = True

    def __post_init__(self) -> None:
        store(self, "tol", check_range("tol", self.tol, 0.0, np.inf))
        for name in ("atol_step", "rtol_step"):
            store(self, name, check_range(name, getattr(self, name), 0.0, 1.0, hi_open=True))
        if self.atol_step == 0.0 and self.rtol_step == 0.0:
            raise ValueError("atol_step and rtol_step cannot both be 0 (no step would ever be small)")
        store(self, "max_iter", check_range("max_iter", self.max_iter, 1, 1000, integer=True))
        store(self, "divergence", check_range("divergence", self.divergence, 1.0, np.inf, lo_open=True))
        store(self, "verify_residual", check_flag("verify_residual", self.verify_residual))


class NewtonSolution(eqx.Module):
    """Result of a Newton solve.

    x: the converged point, or the last finite iterate; aux: the by-product of ``linearise`` at ``x`` (valid when
    converged with ``verify_residual``); code: :class:`Outcome` as an integer (use :attr:`outcome`);
    iterations: Newton steps taken; residual: max-norm of the residual at the last evaluation; step: max-norm of
    the last step.  Arrays, so that the solution of a vmapped solve holds every member on the leading axis.
    """

    x: Any
    aux: Any
    code: Any
    iterations: Any
    residual: Any
    step: Any

    @property
    def outcome(self) -> Outcome:
        return Outcome.from_code(self.code)

    @property
    def converged(self) -> Any:
        """``code == CONVERGED`` (a boolean array: also usable on traced and batched solutions)."""
        return jnp.asarray(self.code) == Outcome.CONVERGED.code


class _State(eqx.Module):
    x: Any
    it: Any
    rnorm: Any
    dnorm: Any
    best: Any
    pending: Any
    code: Any


def _tree_max_abs(tree: Any) -> jax.Array:
    leaves = [jnp.max(jnp.abs(a)) for a in jax.tree_util.tree_leaves(tree) if jnp.size(a)]
    return jnp.max(jnp.stack(leaves)) if leaves else jnp.asarray(0.0)


def _accepts(s: _State, rnorm, cfg: NewtonSettings):
    """Whether an evaluation with residual ``rnorm`` ends the iteration as converged (the residual check)."""
    return s.pending & jnp.isfinite(rnorm) & (rnorm <= jnp.maximum(cfg.tol, 10.0 * s.rnorm))


def _advance(s: _State, rnorm, dx, t_fn, aux, scale_fn, cfg: NewtonSettings) -> tuple[_State, Any]:
    """One transition of the iteration (see the module docstring); works on traced and on concrete values.
    Returns the new state and whether the evaluation just made converged (its ``aux`` belongs to the result)."""
    dnorm = _tree_max_abs(dx)
    converged = _accepts(s, rnorm, cfg)
    finite = jnp.isfinite(rnorm) & jnp.isfinite(dnorm)
    diverged = (s.it >= 2) & (dnorm > cfg.divergence * s.best)
    exhausted = s.it >= cfg.max_iter
    # a step that already passes the small-step test is taken in full: damping compares rounding noise there
    t = jnp.where(dnorm <= cfg.atol_step + cfg.rtol_step * scale_fn(s.x), 1.0, jnp.asarray(t_fn(s.x, dx, aux)))
    no_step = jnp.logical_not(t > 0.0)
    code = jnp.where(converged, Outcome.CONVERGED.code,
           jnp.where(~finite, Outcome.NONFINITE.code,
           jnp.where(diverged, Outcome.DIVERGED.code,
           jnp.where(exhausted, Outcome.MAX_ITERATIONS.code,
           jnp.where(no_step, Outcome.NONFINITE.code, _RUNNING)))))
    go = code == _RUNNING
    x_new = jax.tree_util.tree_map(lambda a, b: jnp.where(go, a + t * b, a), s.x, dx)
    small = (t == 1.0) & (dnorm <= cfg.atol_step + cfg.rtol_step * scale_fn(x_new))
    if not cfg.verify_residual:
        code = jnp.where(go & small, Outcome.CONVERGED.code, code)
    new = _State(x=x_new, it=s.it + jnp.where(go, 1, 0), rnorm=jnp.where(finite | converged, rnorm, s.rnorm),
                 dnorm=jnp.where(converged, s.dnorm, dnorm), best=jnp.where(go, jnp.minimum(s.best, dnorm), s.best),
                 pending=go & small, code=code)
    return new, converged | (go & small & (not cfg.verify_residual))


def _full_step(x, dx, aux):
    return jnp.asarray(1.0)


def _init(x0) -> _State:
    inf = jnp.asarray(jnp.inf)
    return _State(x=x0, it=jnp.asarray(0), rnorm=inf, dnorm=inf, best=inf, pending=jnp.asarray(False),
                  code=jnp.asarray(_RUNNING))


def _solution(s: _State, aux: Any) -> NewtonSolution:
    return NewtonSolution(x=s.x, aux=aux, code=s.code, iterations=s.it, residual=s.rnorm, step=s.dnorm)


def solve(linearise: Callable[[Any], tuple[Any, Any, Any]], x0: Any, settings: NewtonSettings, *,
          damping: Callable[[Any, Any, Any], Any] | None = None,
          scale: Callable[[Any], Any] = _tree_max_abs) -> NewtonSolution:
    """Newton's method as a ``lax.while_loop`` (pure JAX: call it inside ``jax.jit``; ``jax.vmap`` batches it).

    ``linearise(x) -> (rnorm, dx, aux)`` must be traceable; ``damping(x, dx, aux) -> t`` in [0, 1] (default 1);
    ``scale(x)`` the magnitude in the relative step test (default: max |leaf|).  Returns :class:`NewtonSolution`.
    """
    t_fn = damping or _full_step
    aux0 = jax.tree_util.tree_map(lambda a: jnp.zeros(a.shape, a.dtype),
                                  jax.eval_shape(lambda x: linearise(x)[2], x0))

    def body(carry):
        s, aux_kept = carry
        rnorm, dx, aux = linearise(s.x)
        s, take = _advance(s, rnorm, dx, t_fn, aux, scale, settings)
        return s, jax.tree_util.tree_map(lambda a, b: jnp.where(take, b, a), aux_kept, aux)

    s, aux = jax.lax.while_loop(lambda c: c[0].code == _RUNNING, body, (_init(x0), aux0))
    return _solution(s, aux)


def with_finite_tangent(sol: NewtonSolution) -> NewtonSolution:
    """``sol``, or when it converged with a tangent (``aux``, any pytree of arrays) that is not finite, the same
    ended NONFINITE.  A correction that lands exactly on a branch point converges (the residual vanishes) while
    the bordered system that gives the tangent is singular; its NaN tangent made the next analysis fail
    ("SVD did not converge") and lost the whole branch.  As NONFINITE the driver treats it as any failed
    correction (a shorter step, or the next trial point of a localisation).  Host-side, on concrete arrays."""
    if not bool(sol.converged):
        return sol
    if all(np.all(np.isfinite(np.asarray(a))) for a in jax.tree_util.tree_leaves(sol.aux)):
        return sol
    return NewtonSolution(x=sol.x, aux=sol.aux, code=Outcome.NONFINITE.code, iterations=sol.iterations,
                          residual=sol.residual, step=sol.step)


def solve_host(linearise: Callable[..., tuple[Any, Any, Any]], x0: Any, settings: NewtonSettings, *,
               damping: Callable[[Any, Any, Any], Any] | None = None,
               scale: Callable[[Any], Any] = _tree_max_abs, knows_acceptance: bool = False) -> NewtonSolution:
    """The same iteration as :func:`solve`, stepped from Python (``linearise`` may use host linear algebra).

    With ``knows_acceptance`` it is called as ``linearise(x, accepts)``, where ``accepts(rnorm) -> bool`` says
    whether that residual ends the iteration as converged: the step is then never taken, and an expensive solve
    for it can be skipped (return any ``dx`` of the right structure).

    A :class:`LinearSolveError` from ``linearise`` ends the solve with ``Outcome.LINEAR_SOLVE_FAILED`` (the last
    iterate is returned); every other exception propagates."""
    t_fn = damping or _full_step
    s, kept = _init(x0), None
    while True:
        try:
            if knows_acceptance:
                state = s
                rnorm, dx, aux = linearise(s.x, lambda r: bool(_accepts(state, jnp.asarray(r), settings)))
            else:
                rnorm, dx, aux = linearise(s.x)
        except LinearSolveError:
            return NewtonSolution(x=s.x, aux=None, code=Outcome.LINEAR_SOLVE_FAILED.code, iterations=s.it,
                                  residual=s.rnorm, step=s.dnorm)
        s, take = _advance(s, jnp.asarray(rnorm), dx, t_fn, aux, scale, settings)
        if bool(take):
            kept = aux
        if int(s.code) != _RUNNING:
            return _solution(s, kept)
