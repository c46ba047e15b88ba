r"""Sensitivities of a converged periodic orbit to the fixed parameters ``args`` by the implicit function theorem.

At a converged orbit u (collocation unknowns, period T) of ``G(u, theta) = 0`` at fixed lam, with ``theta`` a
direction in ``args`` (e.g. one foil property), the orbit moves by

.. math:: J\,\frac{du}{d\theta} = -\frac{\partial G}{\partial\theta}

with J the *same* Jacobian the Newton corrector factorises (collocation rows, periodicity, phase condition, lam
fixed): one condensed linear solve per parameter, never a derivative through Newton iterates.  Functionals
``F(u, theta)`` (e.g. the cycle energy, pure JAX) then have :math:`dF/d\theta = F_u\,du/d\theta + F_\theta`, a
forward-mode ``jax.jvp``.

Floquet multipliers: for a simple eigenvalue mu of the monodromy matrix M with right and left eigenvectors v, w,
:math:`d\mu = w^T dM\,v / (w^T v)`.  ``dM v`` along a direction ``(du, dtheta)`` is the response of the
linearised collocation equations: with :math:`\Phi` the variational solution started at v (one sweep),
:math:`L\,\delta\Phi = -(\partial_{(u,\theta)} L)\Phi`, :math:`\delta\phi_0 = 0`, where the right-hand side is a
second-order ``jax.jvp`` of the collocation residual; dense backend: ``jax.jvp`` of the product of the transfer
matrices.  Left eigenvectors: ARPACK on :math:`M^T` (transposed sweeps) or ``scipy.linalg.eig``.

Two modes.  *Tangent* (``orbit_sensitivities`` + ``functional_derivatives`` / ``multiplier_derivatives``): one
condensed solve per parameter direction, for all functionals at once; the only mode of the sparse backend.
*Adjoint* (``adjoint_gradient``, dense backend): one transposed condensed solve per functional,

.. math:: J^T\lambda = \partial F/\partial u,\qquad \frac{dF}{d\theta} = \frac{\partial F}{\partial\theta}
          - \lambda^T \frac{\partial G}{\partial\theta},

giving the gradient with respect to *every* leaf of ``args`` at once.  The transposed solve is the pullback
(``jax.vjp``) of the corrector's own condensed solve, linear in its right-hand side, so J is never formed.  The
modulus of the leading multiplier enters as the functional ``Re(conj(mu) w^T M(u, theta) v / (w^T v)) / |mu|``
with the eigenvectors held fixed, whose total derivative is d|mu| (first-order perturbation of a simple eigenvalue).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import Any, Callable, Sequence

import jax
import jax.numpy as jnp
import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla

from . import collocation as col
from .floquet import trivial_index
from .problem import CycleProblem

__all__ = ["orbit_sensitivities", "functional_derivatives", "multiplier_derivatives", "leading_nontrivial",
           "adjoint_gradient", "MultiplierModulus"]


@partial(jax.jit, static_argnums=(0, 4))
def _param_rhs(f, args, dargs, orbit, scheme):
    """-dG/dtheta (collocation rows) for each direction stacked on the leading axis of ``dargs``."""
    def one(d):
        return -jax.jvp(lambda a: col.collocation_residual(f, a, orbit, scheme), (args,), (d,))[1]
    return jax.vmap(one)(dargs)


_solve_multi = jax.jit(col.linear_solve_multi, static_argnums=(0, 4))


def _as_tangent(o: col.Orbit) -> col.Orbit:
    """An orbit used as a jvp direction: the mesh is a leaf of the pytree but not an unknown (zero tangent)."""
    return col.Orbit(jnp.zeros_like(o.mesh), o.xm, o.xi, jnp.asarray(o.T), jnp.asarray(o.lam))


def _stack(dargs: Sequence[Any]) -> Any:
    return jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *dargs)


def orbit_sensitivities(problem: CycleProblem, backend: Any, orbit: col.Orbit, dargs: Sequence[Any],
                        scheme: col.Scheme) -> list[col.Orbit]:
    """du/dtheta_k (orbit-shaped; lam component 0) for each direction ``dargs[k]`` (a pytree like
    ``problem.args``), at fixed lam = ``orbit.lam``."""
    con = col.natural_constraint(orbit, orbit.lam)
    rc = np.asarray(_param_rhs(problem.f, problem.args, _stack(dargs), orbit, scheme))  # (k, N, m, n)
    k, n = rc.shape[0], problem.n
    if hasattr(backend, "linearise"):  # sparse: one factorisation, k GMRES solves
        lin = backend.linearise(orbit, con)
        return [lin.solve(rc[i], np.zeros(n), np.zeros(2), backend.gmres_rtol) for i in range(k)]
    dxm, dw, dp = _solve_multi(problem.f, problem.args, orbit, con, scheme, jnp.moveaxis(jnp.asarray(rc), 0, -1),
                               jnp.zeros((n, k)), jnp.zeros((2, k)))
    return [col.Orbit(orbit.mesh, dxm[..., i], dw[..., i], dp[0, i], dp[1, i]) for i in range(k)]


def functional_derivatives(F: Callable[[col.Orbit, Any], Any], orbit: col.Orbit, args: Any,
                           tangents: Sequence[col.Orbit], dargs: Sequence[Any]) -> np.ndarray:
    """Total derivatives dF/dtheta_k = F_u du_k + F_theta dtheta_k of a pure-JAX functional ``F(orbit, args)``
    (scalar or array), stacked on the first axis.  Keep the same ``F`` object between calls (it is a static
argument of the compiled derivative)."""
    return np.stack([np.asarray(_jvp(F, orbit, args, _as_tangent(t), d)) for t, d in zip(tangents, dargs)])


@partial(jax.jit, static_argnums=(0,))
def _jvp(F, orbit, args, do, da):
    return jax.jvp(F, (orbit, args), (do, da))[1]


def leading_nontrivial(mu: np.ndarray, n_trivial: int = 1) -> int:
    """Index in ``mu`` of the largest-modulus multiplier once the ``n_trivial`` closest to +1 are removed."""
    mu = np.asarray(mu)
    drop = set(np.atleast_1d(trivial_index(mu, n_trivial)).tolist())
    idx = [i for i in np.argsort(-np.abs(mu), kind="stable") if i not in drop]
    return int(idx[0])


# ---------------------------------------------------------------- multipliers
def _monodromy(f, args, orbit, scheme):
    G = col.transfer_matrices(f, args, orbit, scheme)
    return jax.lax.fori_loop(0, G.shape[0], lambda j, M: G[j] @ M, jnp.eye(G.shape[1], dtype=G.dtype))


@partial(jax.jit, static_argnums=(0, 3))
def _monodromy_jvp(f, args, orbit, scheme, do, da):
    return jax.jvp(lambda o, a: _monodromy(f, a, o, scheme), (orbit, args), (do, da))


def _dense_multiplier(problem, orbit, scheme, tangents, dargs):
    Ms = [_monodromy_jvp(problem.f, problem.args, orbit, scheme, _as_tangent(t), d) for t, d in zip(tangents, dargs)]
    M = np.asarray(Ms[0][0])
    ev, vl, vr = sla.eig(M, left=True, right=True)
    i = leading_nontrivial(ev, problem.n_trivial)
    w, v = vl[:, i].conj(), vr[:, i]
    return ev[i], [complex(w @ np.asarray(dM) @ v / (w @ v)) for _, dM in Ms]


@partial(jax.jit, static_argnums=(0, 4))
def _dL_phi(f, args, orbit, phi, scheme, do, da):
    """(d/d(orbit, args) of the linearised collocation operator along (do, da)) applied to phi: (N, m, n)."""
    def lin(o, a):
        return jax.jvp(lambda oo: col.collocation_residual(f, a, oo, scheme), (o,), (phi,))[1]
    return jax.jvp(lin, (orbit, args), (do, da))[1]


def _sparse_multiplier(problem, backend, orbit, scheme, tangents, dargs):
    lin = backend._cached(orbit)
    n = problem.n
    k = backend.n_multipliers
    M = spla.LinearOperator((n, n), matvec=lin.monodromy_matvec, dtype=float)
    Mt = spla.LinearOperator((n, n), matvec=lin.monodromy_rmatvec, dtype=float)
    ncv = min(n, max(2 * k + 1, 30))
    ev, V = spla.eigs(M, k=k, which="LM", tol=1e-11, ncv=ncv, maxiter=50 * n)
    i = leading_nontrivial(ev, problem.n_trivial)
    mu, v = ev[i], V[:, i]
    evt, W = spla.eigs(Mt, k=k, which="LM", tol=1e-11, ncv=ncv, maxiter=50 * n)
    j = int(np.argmin(np.abs(evt - mu)))
    if abs(evt[j] - mu) > 1e-6 * max(1.0, abs(mu)):
        raise RuntimeError(f"left eigenvector of multiplier {mu} not found (closest {evt[j]})")
    w = W[:, j]  # M^T w = mu w  =>  w^T M = mu w^T

    def phi_of(x0):
        xm, wi = lin.sweep(np.asarray(x0, float), np.zeros(2))
        return col.Orbit(jnp.zeros_like(orbit.mesh), jnp.asarray(xm), jnp.asarray(wi), jnp.asarray(0.0),
                         jnp.asarray(0.0))

    phis = (phi_of(v.real), phi_of(v.imag))
    out = []
    for t, d in zip(tangents, dargs):
        dMv = []
        for phi in phis:
            c = -np.asarray(_dL_phi(problem.f, problem.args, orbit, phi, scheme, _as_tangent(t), d)
                            ).reshape(orbit.N, -1)
            dMv.append(lin.sweep(np.zeros(n), np.zeros(2), c)[0][-1])
        out.append(complex(w @ (dMv[0] + 1j * dMv[1]) / (w @ v)))
    return mu, out


def multiplier_derivatives(problem: CycleProblem, backend: Any, orbit: col.Orbit, scheme: col.Scheme,
                           tangents: Sequence[col.Orbit], dargs: Sequence[Any]) -> tuple[complex, list[complex]]:
    """The leading non-trivial Floquet multiplier mu of ``orbit`` and its total derivatives d mu / d theta_k
    (orbit sensitivities ``tangents`` from :func:`orbit_sensitivities`).  d|mu| = Re(conj(mu) d mu) / |mu|."""
    if hasattr(backend, "linearise"):
        return _sparse_multiplier(problem, backend, orbit, scheme, tangents, dargs)
    return _dense_multiplier(problem, orbit, scheme, tangents, dargs)


# ---------------------------------------------------------------- adjoint (dense backend)
@partial(jax.jit, static_argnums=(0, 1, 5))
def _adjoint(f, F, args, orbit, data, scheme):
    con = col.natural_constraint(orbit, orbit.lam)
    Fu, Fa = jax.grad(lambda o, a: F(o, a) if data is None else F(o, a, data), argnums=(0, 1))(orbit, args)

    def solve(rc, rper, rs):  # J^{-1}, linear in the right-hand side
        dxm, dw, dp = col.linear_solve_multi(f, args, orbit, con, scheme, rc[..., None], rper[:, None],
                                             rs[:, None])
        return dxm[..., 0], dw[..., 0], dp[:, 0]

    z = orbit.xm.dtype
    zeros = (jnp.zeros((orbit.N, scheme.m, orbit.n), z), jnp.zeros((orbit.n,), z), jnp.zeros((2,), z))
    lam_c = jax.vjp(solve, *zeros)[1]((Fu.xm, Fu.xi, jnp.stack([Fu.T, Fu.lam])))[0]  # J^-T F_u, collocation rows
    # Only the collocation rows depend on args (periodicity, phase and lam rows do not).
    G_a = jax.vjp(lambda a: col.collocation_residual(f, a, orbit, scheme), args)[1](lam_c)[0]
    return jax.tree_util.tree_map(lambda x, y: x - y, Fa, G_a)


def adjoint_gradient(problem: CycleProblem, orbit: col.Orbit, scheme: col.Scheme, F: Callable[..., Any],
                     data: Any = None) -> Any:
    """dF/d(args) of a scalar pure-JAX functional ``F(orbit, args)`` (or ``F(orbit, args, data)`` with a traced
    pytree ``data``) along the solution at fixed lam, by one transposed condensed solve (dense backend): a
    pytree like ``problem.args``.  ``F`` is a static argument of the compiled kernel: keep the same object."""
    return _adjoint(problem.f, F, problem.args, orbit, data, scheme)


@dataclass(frozen=True)
class MultiplierModulus:
    """The functional ``Re(sum_ij a_ij M_ij(orbit, args))`` with M the monodromy matrix: for
    ``a = conj(mu) (w v^T) / (|mu| w^T v)`` (from :meth:`weights`) its total derivative is d|mu| of the simple
    multiplier mu with right/left eigenvectors v, w.  Use as ``adjoint_gradient(..., MultiplierModulus(f, scheme),
    data=a)``."""

    f: Callable
    scheme: col.Scheme

    def __call__(self, orbit: col.Orbit, args: Any, a: jax.Array) -> jax.Array:
        return jnp.real(jnp.sum(a * _monodromy(self.f, args, orbit, self.scheme)))

    def weights(self, problem: CycleProblem, orbit: col.Orbit) -> tuple[complex, jax.Array]:
        """The leading non-trivial multiplier mu of ``orbit`` and the weights ``a`` (dense eigen-decomposition)."""
        M = np.asarray(_monodromy_jit(self.f, problem.args, orbit, self.scheme))
        ev, vl, vr = sla.eig(M, left=True, right=True)
        i = leading_nontrivial(ev, problem.n_trivial)
        mu, v, w = ev[i], vr[:, i], vl[:, i].conj()
        return mu, jnp.asarray(np.outer(w, v) * np.conj(mu) / (abs(mu) * (w @ v)))


_monodromy_jit = jax.jit(_monodromy, static_argnums=(0, 3))
