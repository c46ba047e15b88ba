r"""Sensitivities of a converged periodic orbit to the fixed parameters ``args`` by the implicit function theorem.

At a converged orbit u (collocation unknowns, period T) of ``G(u, theta) = 0`` at fixed lam, with ``theta`` a
direction in ``args`` (e.g. one foil property), the orbit moves by

.. math:: J\,\frac{du}{d\theta} = -\frac{\partial G}{\partial\theta}

with J the *same* Jacobian the Newton corrector factorises (collocation rows, periodicity, phase condition, lam
fixed): linear solves with the corrector's :class:`~._linear.Linearisation`, never a derivative through Newton
iterates.  Everything here works through that protocol, so on both linear solvers.

Floquet multipliers: for a simple eigenvalue mu of the monodromy matrix M with right and left eigenvectors v, w,
:math:`d\mu = w^T dM\,v / (w^T v)`.  With :math:`\Phi` the variational solution started at v (one sweep), a change
d of (u, theta) gives :math:`L\,\delta\Phi = -(\partial_{(u,\theta)} L\cdot d)\Phi`, :math:`\delta\phi_0 = 0`,
and :math:`dMv = \delta\phi_N`; the right-hand side is a second-order ``jax.jvp`` of the collocation residual.

Two modes.

* *Tangent* (:func:`orbit_sensitivities` + :func:`functional_derivatives` / :func:`multiplier_derivatives`): one
  solve per parameter direction, for all functionals at once.
* *Adjoint* (:func:`adjoint_gradient`, :func:`multiplier_gradient`): one transposed solve per functional,

  .. math:: J^T\lambda = \partial F/\partial u,\qquad \frac{dF}{d\theta} = \frac{\partial F}{\partial\theta}
            - \lambda^T \frac{\partial G}{\partial\theta},

  giving the gradient with respect to *every* leaf of ``args`` at once.  For the multiplier modulus the partial
  derivatives come from one adjoint sweep :math:`\psi` (:math:`\sum_j\psi_j\cdot c_j = w\cdot x_N`):
  :math:`w^T dM v = -\psi^T (\partial L\cdot d)\Phi`, a ``jax.vjp`` of :math:`(u,\theta)\mapsto L(u,\theta)\Phi`.
"""
from __future__ import annotations

from functools import partial
from typing import Any, Callable, Sequence

import jax
import jax.numpy as jnp
import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla

from . import _collocation as col
from ._floquet import trivial_index
from ._linear import Linearisation
from ._problem import CycleProblem

__all__ = ["orbit_sensitivities", "functional_derivatives", "multiplier_derivatives", "adjoint_gradient",
           "multiplier_gradient", "leading_nontrivial", "leading_multiplier"]

#: Up to this state count the leading multiplier's eigenvectors come from the explicit monodromy matrix (n solves
#: per interval); above it from Arnoldi on the monodromy operator and its transpose.
DENSE_EIG_MAX_N = 200


@partial(jax.jit, static_argnums=(0, 4))
def _param_rhs(f, args, dargs, orbit, scheme):
    """-dG/dtheta (collocation rows) for each direction stacked on the leading axis of ``dargs``."""
    def one(d):
        return -jax.jvp(lambda a: col.collocation_residual(f, a, orbit, scheme), (args,), (d,))[1]
    return jax.vmap(one)(dargs)


def _as_tangent(o: col.Orbit) -> col.Orbit:
    """An orbit used as a jvp direction: the mesh is a leaf of the pytree but not an unknown (zero tangent)."""
    return col.Orbit(jnp.zeros_like(o.mesh), o.xm, o.xi, jnp.asarray(o.T), jnp.asarray(o.lam))


def _stack(dargs: Sequence[Any]) -> Any:
    return jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *dargs)


def orbit_sensitivities(problem: CycleProblem, lin: Linearisation, dargs: Sequence[Any],
                        scheme: col.Scheme) -> list[col.Orbit]:
    """du/dtheta_k (orbit-shaped; lam component 0) for each direction ``dargs[k]`` (a pytree like
    ``problem.args``), at fixed lam, with ``lin`` the linearisation of the converged orbit at fixed lam."""
    rc = _param_rhs(problem.f, problem.args, _stack(dargs), lin.orbit, scheme)  # (k, N, m, n)
    return lin.solve_many(rc)


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


def leading_multiplier(problem: CycleProblem, lin: Linearisation, k: int = 12
                       ) -> tuple[complex, np.ndarray, np.ndarray]:
    """The leading non-trivial multiplier mu with right and left eigenvectors v (M v = mu v) and w
    (w^T M = mu w^T): dense eigen-decomposition of M for n <= DENSE_EIG_MAX_N, else Arnoldi on M and M^T."""
    n = problem.n
    if n <= DENSE_EIG_MAX_N:
        M = np.eye(n)
        for g in lin.transfer_matrices():
            M = g @ M
        ev, vl, vr = sla.eig(M, left=True, right=True)
        i = leading_nontrivial(ev, problem.n_trivial)
        return complex(ev[i]), vr[:, i], vl[:, i].conj()
    k = min(k, n - 2)
    ncv = min(n, max(2 * k + 1, 30))
    M = spla.LinearOperator((n, n), matvec=lin.monodromy_matvec, dtype=float)
    Mt = spla.LinearOperator((n, n), matvec=lin.monodromy_rmatvec, dtype=float)
    ev, V = spla.eigs(M, k=k, which="LM", tol=1e-11, ncv=ncv, maxiter=50 * n)
    i = leading_nontrivial(ev, problem.n_trivial)
    mu, v = ev[i], V[:, i]
    evt, W = spla.eigs(Mt, k=k, which="LM", tol=1e-11, ncv=ncv, maxiter=50 * n)
    j = int(np.argmin(np.abs(evt - mu)))
    if abs(evt[j] - mu) > 1e-6 * max(1.0, abs(mu)):
        raise RuntimeError(f"left eigenvector of multiplier {mu} not found (closest {evt[j]})")
    return complex(mu), v, W[:, j]  # M^T w = mu w  =>  w^T M = mu w^T


def _variational(lin: Linearisation, x0: np.ndarray) -> col.Orbit:
    """The variational solution Phi from x0 at fixed (T, lam), orbit-shaped, as a jvp direction."""
    xm, wi = lin.sweep(np.asarray(x0, float), np.zeros(2))
    return col.Orbit(jnp.zeros_like(lin.orbit.mesh), jnp.asarray(xm), jnp.asarray(wi), jnp.asarray(0.0),
                     jnp.asarray(0.0))


@partial(jax.jit, static_argnums=(0, 4))
def _dL_phi(f, args, orbit, phi, scheme, do, da):
    """(d/d(orbit, args) of the linearised collocation operator along (do, da)) applied to phi: (N, m, n)."""
    def lin(o, a):
        return jax.jvp(lambda oo: col.collocation_residual(f, a, oo, scheme), (o,), (phi,))[1]
    return jax.jvp(lin, (orbit, args), (do, da))[1]


def multiplier_derivatives(problem: CycleProblem, lin: Linearisation, scheme: col.Scheme,
                           tangents: Sequence[col.Orbit], dargs: Sequence[Any]) -> tuple[complex, list[complex]]:
    """The leading non-trivial Floquet multiplier mu of ``lin.orbit`` and its total derivatives d mu / d theta_k
    (orbit sensitivities ``tangents`` from :func:`orbit_sensitivities`).  d|mu| = Re(conj(mu) d mu) / |mu|."""
    mu, v, w = leading_multiplier(problem, lin)
    n, orbit = problem.n, lin.orbit
    phis = (_variational(lin, v.real), _variational(lin, v.imag))
    out = []
    for t, d in zip(tangents, dargs):
        dMv = []
        for phi in phis:
            c = -np.asarray(_dL_phi(problem.f, problem.args, orbit, phi, scheme, _as_tangent(t), d)
                            ).reshape(orbit.N, -1)
            dMv.append(lin.sweep(np.zeros(n), np.zeros(2), c)[0][-1])
        out.append(complex(w @ (dMv[0] + 1j * dMv[1]) / (w @ v)))
    return mu, out


# ---------------------------------------------------------------- adjoint
@partial(jax.jit, static_argnums=(0,))
def _partials(F, orbit, args, data):
    return jax.grad(lambda o, a: F(o, a) if data is None else F(o, a, data), argnums=(0, 1))(orbit, args)


@partial(jax.jit, static_argnums=(0, 3))
def _G_args_vjp(f, args, orbit, scheme, lam_c):
    return jax.vjp(lambda a: col.collocation_residual(f, a, orbit, scheme), args)[1](lam_c)[0]


def _total(problem: CycleProblem, lin: Linearisation, scheme: col.Scheme, Fu: col.Orbit, Fa: Any) -> Any:
    """dF/d(args) from the partial derivatives: Fa - (dG/dargs)^T J^{-T} Fu (only the collocation rows of G
    depend on args; periodicity, phase and lam rows do not)."""
    lam_c = lin.solve_transpose(Fu)[0]
    G_a = _G_args_vjp(problem.f, problem.args, lin.orbit, scheme, jnp.asarray(lam_c))
    return jax.tree_util.tree_map(lambda x, y: x - y, Fa, G_a)


def adjoint_gradient(problem: CycleProblem, lin: Linearisation, scheme: col.Scheme, F: Callable[..., Any],
                     data: Any = None) -> Any:
    """dF/d(args) of a scalar pure-JAX functional ``F(orbit, args)`` (or ``F(orbit, args, data)`` with a traced
    pytree ``data``) along the solution at fixed lam, by one transposed solve with the linearisation ``lin`` of
    the converged orbit at fixed lam (either linear solver): a pytree like ``problem.args``.  ``F`` is a static
    argument of the compiled kernel: keep the same object."""
    Fu, Fa = _partials(F, lin.orbit, problem.args, data)
    return _total(problem, lin, scheme, Fu, Fa)


@partial(jax.jit, static_argnums=(0, 3))
def _psi_L_phi_vjp(f, args, orbit, scheme, phi, psi):
    """-vjp of (orbit, args) -> L(orbit, args) phi applied to psi (N, m, n): the partials of psi^T c."""
    def L_phi(o, a):
        return jax.jvp(lambda oo: col.collocation_residual(f, a, oo, scheme), (o,), (phi,))[1]
    go, ga = jax.vjp(L_phi, orbit, args)[1](psi)
    neg = lambda t: jax.tree_util.tree_map(jnp.negative, t)  # noqa: E731
    return neg(go), neg(ga)


def multiplier_gradient(problem: CycleProblem, lin: Linearisation, scheme: col.Scheme) -> tuple[complex, Any]:
    """The leading non-trivial multiplier mu of ``lin.orbit`` and d|mu|/d(args) (a pytree like ``problem.args``)
    by the adjoint: one adjoint sweep for the partials, one transposed solve for the orbit's response."""
    mu, v, w = leading_multiplier(problem, lin)
    orbit, N = lin.orbit, lin.orbit.N
    phis = (_variational(lin, v.real), _variational(lin, v.imag))
    psis = tuple(jnp.asarray(lin.adjoint_sweep(np.ascontiguousarray(p)).reshape(N, scheme.m, problem.n))
                 for p in (w.real, w.imag))
    # w^T dM v = sum over (psi_a, phi_b) with complex weights; then d|mu| = Re(conj(mu) dmu) / |mu|
    wv = complex(w @ v)
    coeff = np.conj(mu) / (abs(mu) * wv)  # d|mu| = Re(coeff * w^T dM v)
    # Re(coeff (A + iB)) with A = G[re,re] - G[im,im], B = G[re,im] + G[im,re]
    weights = {(0, 0): coeff.real, (1, 1): -coeff.real, (0, 1): -coeff.imag, (1, 0): -coeff.imag}
    Fu = Fa = None
    for (a, b), cw in weights.items():
        go, ga = _psi_L_phi_vjp(problem.f, problem.args, orbit, scheme, phis[b], psis[a])
        go = jax.tree_util.tree_map(lambda x: cw * x, go)
        ga = jax.tree_util.tree_map(lambda x: cw * x, ga)
        Fu = go if Fu is None else jax.tree_util.tree_map(jnp.add, Fu, go)
        Fa = ga if Fa is None else jax.tree_util.tree_map(jnp.add, Fa, ga)
    Fu = col.Orbit(orbit.mesh, Fu.xm, Fu.xi, Fu.T, Fu.lam)
    return mu, _total(problem, lin, scheme, Fu, Fa)
