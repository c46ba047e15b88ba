"""Batched (vmapped) Newton for many parameter sets at once, at fixed lam: one compiled step for all members.

For parameter sweeps (maps over design variables): every member starts from the *same* orbit and runs the dense
condensed Newton step of :mod:`collocation`, vmapped over the members (iterations until the slowest member is
done; finished members keep their orbit).  Dense condensation only, so this is
for the moderate state counts where one dense Newton step is cheap (n up to ~100-150 on a CPU).
"""
from __future__ import annotations

from functools import partial
from typing import Any, Callable

import jax
import jax.numpy as jnp

from . import collocation as col

__all__ = ["batched_newton"]


@partial(jax.jit, static_argnums=(0, 1, 5))
def _step(f, make_args, thetas, base, orbits, scheme):
    """One Newton step of every member (vmapped); members whose step is not finite keep their orbit."""
    def one(theta, o):
        args = make_args(theta, base)
        con = col.natural_constraint(o, o.lam)
        new, rn, dn, _ = col._step_and_tangent(f, args, o, con, scheme)
        ok = jnp.isfinite(rn) & jnp.isfinite(dn)
        new = jax.tree_util.tree_map(lambda a, b: jnp.where(ok, a, b), new, o)
        return new, jnp.where(ok, dn, jnp.inf), rn

    return jax.vmap(one)(thetas, orbits)


def batched_newton(f: Callable, make_args: Callable[[jax.Array, Any], Any], thetas: jax.Array, base: Any,
                   orbit: col.Orbit, scheme: col.Scheme, *, max_iter: int = 15, tol: float = 1e-9):
    """Solve the cycles of ``f(x, lam, make_args(theta, base))`` at lam = ``orbit.lam`` for every row of
    ``thetas``, all starting from ``orbit``.  ``make_args`` is a pure JAX function, a static argument of the
    compiled kernel (use a module-level function), ``base`` any pytree it needs (traced).  Returns (orbits
    batched on the leading axis, iterations, final residual norm, converged mask).

    The iterations are a short Python loop around one compiled, vmapped step (a ``lax.while_loop`` around the
    condensed step dead-locked XLA:CPU here, like the scan kernel noted in :mod:`gfbjax.cont`)."""
    thetas = jnp.asarray(thetas)
    k = thetas.shape[0]
    orbits = jax.tree_util.tree_map(lambda a: jnp.broadcast_to(a, (k,) + jnp.shape(a)), orbit)
    its = jnp.zeros(k, int)
    dn = jnp.full(k, jnp.inf)
    rn = jnp.full(k, jnp.inf)
    for _ in range(int(max_iter)):
        active = dn > tol
        if not bool(jnp.any(active)):
            break
        new, dn_new, rn_new = _step(f, make_args, thetas, base, orbits, scheme)
        orbits = jax.tree_util.tree_map(lambda a, b: jnp.where(_bcast(active, a), a, b), new, orbits)
        dn = jnp.where(active, dn_new, dn)
        rn = jnp.where(active, rn_new, rn)
        its = its + active
    _, _, rn_fin = _step(f, make_args, thetas, base, orbits, scheme)  # residual at the final iterates
    ok = jnp.isfinite(rn_fin) & (rn_fin <= 10 * tol) & (dn <= tol)
    return orbits, its, rn_fin, ok


def _bcast(mask, a):
    return mask.reshape(mask.shape + (1,) * (a.ndim - 1))
