r"""Collocation Newton and Floquet multipliers for *large, sparse* vector fields.

The dense condensation of ``collocation.py`` costs :math:`O(N (mn)^3)` per linearisation: at n = 433 states and
m = 4 that is ~15 s on a 2-core CPU, because the per-interval blocks of size :math:`mn` are treated as dense.  When
``df/dx`` is sparse (film pressures couple only to their grid neighbours) this module keeps the same collocation
equations (27)-(30) and solves the same Newton system another way:

1. **Per-interval sparse LU.**  On interval j, with the left mesh value :math:`x_j` given, the m collocation
   equations determine the m unknown node blocks :math:`(u_{j,1..m-1}, x_{j+1})`:

   .. math:: K_j\,[\delta w_j;\ \delta x_{j+1}] = c_j - A_{L,j}\,\delta x_j - B_{p,j}\,\delta p,

   :math:`K_j = [A_I\ A_R]` (square, :math:`mn`) assembled in compressed-column form from the Jacobian values at
   the Gauss points (column colouring: :mod:`.sparsity`) and factorised by SuperLU.  A *sweep* over
   j = 0..N-1 maps :math:`(\delta x_0, \delta p)` to the whole linearised orbit: multiple shooting with implicit
   (collocation) steps, stable because each step solves the stiff film modes implicitly.
2. **Matrix-free reduced system.**  Periodicity :math:`\delta x_0 - \delta x_N = c_{per}` and the two scalar rows
   (phase (29), continuation (30)) are n + 2 equations in :math:`(\delta x_0, \delta p)`; they are solved by GMRES
   whose matrix-vector product is one sweep.  The reduced operator is
   :math:`[I - M,\ -g;\ \phi^T,\ \psi]` with M the monodromy matrix: its eigenvalues cluster at 1 (the stiff,
   strongly damped multipliers are ~0), so GMRES needs about as many iterations as there are multipliers
   that are not small.
3. **Floquet multipliers** are the leading eigenvalues of M, by ARPACK's implicitly restarted Arnoldi
   (``scipy.sparse.linalg.eigs``), one homogeneous sweep per product.  Only the ``n_multipliers`` largest in
   modulus are returned: they decide stability, and the rest are below any bifurcation's reach.

Per linearisation the cost is N sparse LU factorisations of size mn plus a few tens of sweeps, all linear in N.
The Newton semantics (convergence test, failure reasons, tangent) are those of :func:`collocation.newton`.
"""
from __future__ import annotations

import hashlib
from functools import partial
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from . import collocation as col
from .sparsity import Coloring, color_pattern, jacobian_values


class SolveError(RuntimeError):
    """A linear solve inside Newton failed (singular block, GMRES breakdown)."""


@partial(jax.jit, static_argnums=(0, 3, 4))
def _linear_data(f, args, orbit: col.Orbit, scheme: col.Scheme, coloring_key, Kperm, isdiag):
    """Compressed values of K_j (CSC order), A_{L,j} (row-major pattern order) and B_{p,j} for all intervals."""
    coloring = _COLORINGS[coloring_key]
    m = scheme.m
    U = orbit.nodes()
    h = jnp.diff(orbit.mesh)
    X = jnp.einsum("ki,jin->jkn", scheme.l, U)  # (N, m, n)
    lam = orbit.lam

    def at_point(x):
        fx = f(x, lam, args)
        jv = jacobian_values(lambda y: f(y, lam, args), x, coloring)
        fl = jax.jvp(lambda l_: f(x, l_, args), (lam,), (jnp.ones_like(lam),))[1]
        return fx, jv, fl

    Fx, Jv, Fl = jax.vmap(jax.vmap(at_point))(X)  # (N,m,n), (N,m,nnz), (N,m,n)
    hT = (h * orbit.T)[:, None, None, None]
    l_, dl_ = jnp.asarray(scheme.l), jnp.asarray(scheme.dl)
    # block (k, i) of the interval matrix: dl[k,i] I - h T l[k,i] J(x_jk)
    blocks = dl_[None, :, :, None] * isdiag[None, None, None, :] - hT * l_[None, :, :, None] * Jv[:, :, None, :]
    Kdata = blocks[:, :, 1:, :].reshape(blocks.shape[0], -1)[:, Kperm]
    ALdata = blocks[:, :, 0, :].reshape(blocks.shape[0], -1)
    Bp = jnp.stack([-(h[:, None, None] * Fx), -(h * orbit.T)[:, None, None] * Fl], axis=-1)
    return Kdata, ALdata, Bp.reshape(Bp.shape[0], m * Fx.shape[-1], 2)


_COLORINGS: dict[tuple[int, str], Coloring] = {}
_residual = jax.jit(col.residual, static_argnums=(0, 4))
_coeffs = jax.jit(col._functional_coeffs, static_argnums=(2,))


class _Linearisation:
    """Factorised interval blocks at one orbit, and the sweeps and solves built on them."""

    def __init__(self, owner: "SparseCollocation", orbit: col.Orbit):
        o = owner
        self.owner, self.orbit = o, orbit
        Kd, ALd, Bp = (np.asarray(a) for a in _linear_data(o.f, o.args, orbit, o.scheme, o._key,
                                                           o._Kperm, o._isdiag))
        mn, n = o.scheme.m * o.n, o.n
        self.lus, self.AL = [], []
        for j in range(Kd.shape[0]):
            K = sps.csc_matrix((Kd[j], o._K_indices, o._K_indptr), shape=(mn, mn))
            try:
                self.lus.append(spla.splu(K, permc_spec=o.permc_spec))
            except RuntimeError as e:  # "Factor is exactly singular"
                raise SolveError(f"collocation block of interval {j} is singular: {e}") from e
            self.AL.append(sps.csr_matrix((ALd[j], o._AL_indices, o._AL_indptr), shape=(mn, n)))
        self.Bp = Bp
        self.coef = self.cp = None

    def bordered(self, con: col.Constraint, orbit: col.Orbit | None = None) -> "_Linearisation":
        """Use the phase and continuation rows of ``con`` (at ``orbit``, default the linearisation point)."""
        coef, cp, _ = _coeffs(self.orbit if orbit is None else orbit, con, self.owner.scheme)
        self.coef, self.cp = np.asarray(coef), np.asarray(cp)
        return self

    # ---- sweeps
    def sweep(self, dx0: np.ndarray, dp: np.ndarray, c: np.ndarray | None = None):
        """Mesh values (N+1, n) and interior values (N, m-1, n) of the linearised orbit from (dx0, dp)."""
        o = self.owner
        k = (o.scheme.m - 1) * o.n
        xs, ws = [dx0], []
        x = dx0
        for j, lu in enumerate(self.lus):
            rhs = -(self.AL[j] @ x) - self.Bp[j] @ dp
            if c is not None:
                rhs = rhs + c[j]
            z = lu.solve(rhs)
            ws.append(z[:k])
            x = z[k:]
            xs.append(x)
        return np.array(xs), np.array(ws).reshape(len(self.lus), o.scheme.m - 1, o.n)

    def _border(self, xm: np.ndarray, w: np.ndarray, dp: np.ndarray) -> np.ndarray:
        U = np.concatenate([xm[:-1, None], w, xm[1:, None]], axis=1)
        return np.einsum("ajin,jin->a", self.coef, U) + self.cp @ dp

    def solve(self, rc: np.ndarray, rper: np.ndarray, rs: np.ndarray, rtol: float) -> col.Orbit:
        """Solve J delta = (rc, rper, rs) (the Jacobian of ``collocation.residual``; rows of :meth:`bordered`)."""
        o = self.owner
        n = o.n
        c = np.asarray(rc).reshape(len(self.lus), -1)
        xp, wp = self.sweep(np.zeros(n), np.zeros(2), c)
        b = np.concatenate([np.asarray(rper) + xp[-1], np.asarray(rs) - self._border(xp, wp, np.zeros(2))])

        def matvec(v):
            xm, w = self.sweep(v[:n], v[n:])
            return np.concatenate([v[:n] - xm[-1], self._border(xm, w, v[n:])])

        A = spla.LinearOperator((n + 2, n + 2), matvec=matvec, dtype=float)
        bn = float(np.linalg.norm(b))
        if bn == 0.0:
            v = np.zeros(n + 2)
        else:
            v, info = spla.gmres(A, b, rtol=rtol, atol=0.0, restart=min(n + 2, o.gmres_restart),
                                 maxiter=o.gmres_maxiter)
            if info != 0 or not np.all(np.isfinite(v)):
                raise SolveError(f"GMRES did not converge (info={info})")
        xm, w = self.sweep(v[:n], v[n:], c)
        return col.Orbit(self.orbit.mesh, jnp.asarray(xm), jnp.asarray(w), jnp.asarray(v[n]), jnp.asarray(v[n + 1]))

    def monodromy_matvec(self, v: np.ndarray) -> np.ndarray:
        return self.sweep(np.asarray(v, float), np.zeros(2))[0][-1]

    def monodromy_rmatvec(self, y: np.ndarray) -> np.ndarray:
        """M^T y: the transposed sweep, intervals in reverse order (M = Gamma_{N-1}...Gamma_0,
        Gamma_j = -E K_j^{-1} A_{L,j} with E the last n rows)."""
        k = (self.owner.scheme.m - 1) * self.owner.n
        y = np.asarray(y, float)
        for lu, AL in zip(reversed(self.lus), reversed(self.AL)):
            y = -(AL.T @ lu.solve(np.concatenate([np.zeros(k), y]), trans="T"))
        return y

    def transfer_matrices(self) -> np.ndarray:
        """Gamma_j (N, n, n), mapping dx_j to dx_{j+1} at fixed T, lam (n right-hand sides per interval)."""
        k = (self.owner.scheme.m - 1) * self.owner.n
        return np.array([-lu.solve(AL.toarray())[k:] for lu, AL in zip(self.lus, self.AL)])


class SparseCollocation:
    """Newton corrector, tangent and leading Floquet multipliers for ``x' = f(x, lam, args)`` with a sparse
    Jacobian of known ``pattern`` (boolean (n, n)); see the module docstring.

    n_multipliers: how many Floquet multipliers (largest modulus) :meth:`multipliers` returns;
    gmres_rtol: relative GMRES tolerance of each Newton solve (the Newton test on the true residual decides
    convergence); permc_spec: SuperLU column ordering.
    """

    def __init__(self, f: Any, args: Any, n: int, pattern: np.ndarray, scheme: col.Scheme, *,
                 n_multipliers: int = 12, gmres_rtol: float = 1e-11, gmres_restart: int = 120,
                 gmres_maxiter: int = 20, permc_spec: str = "COLAMD"):
        pattern = np.asarray(pattern, bool)
        if pattern.shape != (n, n):
            raise ValueError(f"jac_sparsity must have shape (n, n) = ({n}, {n}), got {pattern.shape}")
        self.f, self.args, self.n, self.scheme = f, args, n, scheme
        self.n_multipliers = int(min(n_multipliers, n - 2))
        self.gmres_rtol, self.gmres_restart, self.gmres_maxiter = gmres_rtol, gmres_restart, gmres_maxiter
        self.permc_spec = permc_spec
        # one colouring (and one compiled kernel) per pattern, shared by every instance
        self._key = (n, hashlib.sha1(np.packbits(pattern).tobytes()).hexdigest())
        if self._key not in _COLORINGS:
            _COLORINGS[self._key] = color_pattern(pattern)
        self.coloring = _COLORINGS[self._key]
        m, c = scheme.m, self.coloring
        R, C = c.rows, c.cols
        self._isdiag = jnp.asarray((R == C).astype(float))
        # K_j entries in (k, i, entry) order -> CSC
        kk, ii = np.meshgrid(np.arange(m), np.arange(m), indexing="ij")
        rowsK = (kk[..., None] * n + R[None, None]).ravel()
        colsK = (ii[..., None] * n + C[None, None]).ravel()
        perm = np.lexsort((rowsK, colsK))
        self._Kperm = jnp.asarray(perm)
        self._K_indices = rowsK[perm].astype(np.int32)
        self._K_indptr = np.searchsorted(colsK[perm], np.arange(m * n + 1)).astype(np.int32)
        # A_L entries in (k, entry) order are already row-major -> CSR
        rowsA = (np.arange(m)[:, None] * n + R[None]).ravel()
        self._AL_indices = np.tile(C, m).astype(np.int32)
        self._AL_indptr = np.searchsorted(rowsA, np.arange(m * n + 1)).astype(np.int32)
        self._last: _Linearisation | None = None
        self._v0: np.ndarray | None = None  # Arnoldi start (see multipliers)

    # ------------------------------------------------------------------ linearisations
    def linearise(self, orbit: col.Orbit, con: col.Constraint | None = None) -> _Linearisation:
        lin = _Linearisation(self, orbit)
        self._last = lin
        return lin.bordered(con) if con is not None else lin

    def _cached(self, orbit: col.Orbit) -> _Linearisation:
        if self._last is not None and self._last.orbit is orbit:
            return self._last
        return self.linearise(orbit)

    # ------------------------------------------------------------------ Newton
    def newton(self, orbit: col.Orbit, con: col.Constraint, *, tol: float = 1e-10, rtol_step: float = 1e-10,
               max_iter: int = 12, divergence_factor: float = 1e3) -> col.NewtonResult:
        """Newton corrector with the semantics of :func:`collocation.newton` (never a non-finite orbit).

        The tangent of a converged point, and later its multipliers, reuse the linearisation of the last Newton
        iterate, which differs from the converged orbit by the last step (below ``rtol_step``): one sparse
        factorisation per iteration and none extra per point."""
        steps: list[float] = []
        rn = dn = float("inf")
        for it in range(1, max_iter + 1):
            rc, rper, rs = (np.asarray(a) for a in _residual(self.f, self.args, orbit, con, self.scheme))
            rn = max(np.max(np.abs(rc)), np.max(np.abs(rper)), np.max(np.abs(rs)))
            try:
                lin = self.linearise(orbit, con)
                d = lin.solve(-rc, -rper, -rs, self.gmres_rtol)
            except SolveError as e:
                return col.NewtonResult(orbit, col.STATUS_NONFINITE, f"linear solve failed: {e}", it, rn, dn)
            dn = float(np.max(np.abs(np.asarray(d.to_flat()))))
            if not (np.isfinite(rn) and np.isfinite(dn)):
                return col.NewtonResult(orbit, col.STATUS_NONFINITE, col._REASONS[col.STATUS_NONFINITE], it, rn, dn)
            steps.append(dn)
            if len(steps) >= 3 and dn > divergence_factor * min(steps[:-1]):
                return col.NewtonResult(orbit, col.STATUS_DIVERGED, col._REASONS[col.STATUS_DIVERGED], it, rn, dn)
            orbit = orbit + d
            if dn <= rtol_step * (1.0 + float(jnp.max(jnp.abs(orbit.xm)))):
                rc, rper, rs = (np.asarray(a) for a in _residual(self.f, self.args, orbit, con, self.scheme))
                rfin = float(max(np.max(np.abs(rc)), np.max(np.abs(rper)), np.max(np.abs(rs))))
                if np.isfinite(rfin) and (rfin <= tol or rfin <= 10 * rn):
                    try:
                        tan = self._tangent_from(lin, orbit, con)
                    except SolveError as e:
                        return col.NewtonResult(orbit, col.STATUS_NONFINITE, f"tangent solve failed: {e}", it,
                                                rfin, dn)
                    lin.orbit = orbit  # the multipliers of ``orbit`` use this linearisation (see above)
                    return col.NewtonResult(orbit, col.STATUS_CONVERGED, col._REASONS[col.STATUS_CONVERGED], it,
                                            rfin, dn, tan)
                rn = rfin
        return col.NewtonResult(orbit, col.STATUS_MAXITER, col._REASONS[col.STATUS_MAXITER], max_iter, rn, dn)

    def _tangent_from(self, lin: _Linearisation, orbit: col.Orbit, con: col.Constraint) -> col.Orbit:
        N, m, n = orbit.N, self.scheme.m, self.n
        t = lin.bordered(con, orbit).solve(np.zeros((N, m, n)), np.zeros(n), np.array([0.0, 1.0]), self.gmres_rtol)
        return t.scale(1.0 / float(jnp.sqrt(col.inner(t, t, self.scheme))))

    def tangent(self, orbit: col.Orbit, con: col.Constraint) -> col.Orbit:
        """Normalised tangent: J tau = e_cont (orientation fixed by the continuation row of ``con``)."""
        return self._tangent_from(self.linearise(orbit), orbit, con)

    # ------------------------------------------------------------------ Floquet
    def multipliers(self, orbit: col.Orbit, k: int | None = None) -> np.ndarray:
        """The ``k`` (default ``n_multipliers``) Floquet multipliers of largest modulus, sorted decreasing.

        Arnoldi starts from the sum of the previous call's Ritz vectors: along a branch the leading invariant
        subspace moves little between points, and this start saves about a quarter of the sweeps."""
        k = self.n_multipliers if k is None else int(min(k, self.n - 2))
        lin = self._cached(orbit)
        M = spla.LinearOperator((self.n, self.n), matvec=lin.monodromy_matvec, dtype=float)
        v0 = self._v0 if self._v0 is not None else np.ones(self.n) / np.sqrt(self.n)
        for ncv in (max(2 * k + 1, 30), 4 * k + 20):  # a larger Krylov space if ARPACK does not converge
            try:
                mu, V = spla.eigs(M, k=k, which="LM", v0=v0, tol=1e-11, ncv=min(self.n, ncv),
                                  maxiter=50 * self.n)
            except spla.ArpackNoConvergence as e:
                err, v0 = e, np.ones(self.n) / np.sqrt(self.n)
                continue
            v = np.real(V).sum(axis=1) + np.imag(V).sum(axis=1)
            nv = float(np.linalg.norm(v))
            self._v0 = v / nv if np.isfinite(nv) and nv > 0 else None
            return mu[np.argsort(-np.abs(mu), kind="stable")]
        self._v0 = None
        raise SolveError(f"Arnoldi (ARPACK) did not converge for the {k} leading Floquet multipliers: {err}")

    def transfer_matrices(self, orbit: col.Orbit) -> np.ndarray:
        """Gamma_j (N, n, n) at ``orbit`` (n right-hand sides per interval: for branch switching, not per point)."""
        return self._cached(orbit).transfer_matrices()
