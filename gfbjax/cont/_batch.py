"""Batched (vmapped) cycle correction for many parameter sets at once, at fixed lam: the one Newton corrector
(:mod:`._newton`, compiled loop) with the dense condensation, under ``jax.vmap``.

For parameter sweeps (maps over design variables): every member starts from the *same* orbit with the same phase
reference and runs the dense corrector; the convergence rules are those of every other correction.  Under
``jax.vmap`` the loop runs until the slowest member stops (finished members are masked), so on a CPU a Python loop
over members is as fast or faster; the batch pays off on an accelerator, where one step of all members costs
about as much as one.  Dense condensation only: n up to ~100-150.
"""
from __future__ import annotations

from functools import partial
from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from . import _collocation as col
from ._linear import dense_correct
from ._newton import NewtonSettings
from ._results import Outcome

__all__ = ["BatchNewtonResult", "batched_newton"]


class BatchNewtonResult(NamedTuple):
    """Members on the leading axis: ``orbits`` (the converged orbit or the last iterate), ``iterations``,
    ``residual`` (max-norm of the residual at the last evaluation), ``converged`` mask, ``outcomes`` (integer
    :class:`~._results.Outcome` codes) and ``steps`` (member-steps computed in all, finished members included)."""

    orbits: col.Orbit
    iterations: np.ndarray
    residual: np.ndarray
    converged: np.ndarray
    outcomes: np.ndarray
    steps: int


@partial(jax.jit, static_argnums=(0, 1, 5, 6))
def _solve_all(f, make_args, thetas, base, orbit, scheme, newton):
    con = col.natural_constraint(orbit, orbit.lam)
    return jax.vmap(lambda th: dense_correct(f, make_args(th, base), orbit, con, scheme, newton))(thetas)


def batched_newton(f: Callable, make_args: Callable[[jax.Array, Any], Any], thetas: jax.Array, base: Any,
                   orbit: col.Orbit, scheme: col.Scheme, newton: NewtonSettings = NewtonSettings(tol=1e-9,
                   atol_step=1e-9, rtol_step=1e-9, max_iter=10)) -> BatchNewtonResult:
    """Solve the cycles of ``f(x, lam, make_args(theta, base))`` at lam = ``orbit.lam`` for every row of
    ``thetas``, all starting from ``orbit``.  ``make_args`` is a pure JAX function, a static argument of the
    compiled kernel (use a module-level function), ``base`` any pytree it needs (traced)."""
    thetas = jnp.asarray(thetas)
    k = int(thetas.shape[0]) if thetas.ndim else 0
    if k == 0:
        raise ValueError("thetas needs at least one row")
    sol = _solve_all(f, make_args, thetas, base, orbit, scheme, newton)
    codes = np.asarray(sol.code)
    its = np.asarray(sol.iterations)
    ok = codes == Outcome.CONVERGED.code
    return BatchNewtonResult(sol.x, its, np.asarray(sol.residual), ok, codes, int(k * (its.max() + 1)))
