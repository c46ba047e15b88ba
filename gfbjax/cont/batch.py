"""Batched (vmapped) Newton for many parameter sets at once, at fixed lam: one compiled step for all members.

For parameter sweeps (maps over design variables): every member starts from the *same* orbit and runs the dense
condensed Newton step of :mod:`collocation`, vmapped over the members.  The convergence rules are those of
:func:`collocation.newton` (relative step test, then a residual check at the new iterate; a member whose step
grows by ``divergence_factor`` over its smallest one, or turns non-finite, is dropped as failed).  Each iteration
steps only the members still running, gathered into a batch padded to a power of two (so that at most
log2(k) + 1 batch shapes compile).  Dense condensation only: for the moderate state counts where one dense Newton
step is cheap (n up to ~100-150 on a CPU).
"""
from __future__ import annotations

from functools import partial
from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from . import collocation as col

__all__ = ["BatchNewtonResult", "batched_newton"]


class BatchNewtonResult(NamedTuple):
    """Members on the leading axis: ``orbits`` (the last iterate), ``iterations``, ``residual`` (max-norm of
    the residual at the returned orbit), ``converged`` mask and ``steps`` (member-steps computed in all)."""

    orbits: col.Orbit
    iterations: np.ndarray
    residual: np.ndarray
    converged: np.ndarray
    steps: int


@partial(jax.jit, static_argnums=(0, 1, 6))
def _step(f, make_args, thetas, base, orbits, con, scheme):
    """One Newton step of every member (vmapped): (new orbits, residual norm at the old, step norm, max|x| of the
    new mesh values).  ``con`` (shared) fixes lam and the phase against the common start, as collocation.newton
    does."""
    def one(theta, o):
        new, rn, dn, _ = col._step_and_tangent(f, make_args(theta, base), o, con, scheme)
        return new, rn, dn, jnp.max(jnp.abs(new.xm))

    return jax.vmap(one)(thetas, orbits)


def _take(tree, idx):
    return jax.tree_util.tree_map(lambda a: a[idx], tree)


def batched_newton(f: Callable, make_args: Callable[[jax.Array, Any], Any], thetas: jax.Array, base: Any,
                   orbit: col.Orbit, scheme: col.Scheme, *, max_iter: int = 10, tol: float = 1e-9,
                   rtol_step: float = 1e-9, divergence_factor: float = 1e3) -> BatchNewtonResult:
    """Solve the cycles of ``f(x, lam, make_args(theta, base))`` at lam = ``orbit.lam`` for every row of
    ``thetas``, all starting from ``orbit``.  ``make_args`` is a pure JAX function, a static argument of the
    compiled kernel (use a module-level function), ``base`` any pytree it needs (traced)."""
    thetas = jnp.asarray(thetas)
    k = int(thetas.shape[0])
    if k == 0:
        raise ValueError("thetas needs at least one row")
    orbits = jax.tree_util.tree_map(lambda a: jnp.broadcast_to(a, (k,) + jnp.shape(a)), orbit)
    con = col.natural_constraint(orbit, orbit.lam)
    its = np.zeros(k, int)
    best = np.full(k, np.inf)        # smallest step so far (divergence test)
    state = np.zeros(k, int)         # 0 running, 1 step small (residual check pending), 2 done, 3 failed
    rn_out = np.full(k, np.inf)
    steps = 0
    for sweep in range(int(max_iter) + 1):
        run = np.flatnonzero(state < 2)
        if run.size == 0:
            break
        size = 1 << int(np.ceil(np.log2(run.size)))
        idx = np.concatenate([run, np.full(size - run.size, run[0])])
        sub = _take(orbits, idx)
        new, rn, dn, xmax = _step(f, make_args, thetas[idx], base, sub, con, scheme)  # orbits stay on the device
        steps += size
        rn, dn, xmax = (np.asarray(a)[:run.size] for a in (rn, dn, xmax))
        upd = np.zeros(k, bool)
        for j, i in enumerate(run):
            if state[i] == 1:  # residual at the accepted iterate, tested as in collocation.newton
                ok = np.isfinite(rn[j]) and rn[j] <= max(tol, 10 * rn_out[i])
                rn_out[i] = rn[j]
                if ok:
                    state[i] = 2
                    continue
                state[i] = 0
            if sweep == max_iter or not (np.isfinite(rn[j]) and np.isfinite(dn[j])) or (
                    its[i] >= 2 and dn[j] > divergence_factor * best[i]):
                state[i] = 3
                rn_out[i] = rn[j]
                continue
            its[i] += 1
            best[i] = min(best[i], dn[j])
            upd[i] = True
            rn_out[i] = rn[j]
            if dn[j] <= rtol_step * (1.0 + xmax[j]):
                state[i] = 1
        if upd.any():
            pos = np.full(k, -1)
            pos[run] = np.arange(run.size)
            src = jnp.asarray(np.where(upd, pos, 0))
            mask = jnp.asarray(upd)
            orbits = jax.tree_util.tree_map(
                lambda o, n: jnp.where(mask.reshape((k,) + (1,) * (o.ndim - 1)), n[src], o),
                orbits, new)
    ok = state == 2
    return BatchNewtonResult(orbits, its, rn_out, ok, steps)
