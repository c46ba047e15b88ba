r"""Collocation Newton and Floquet multipliers for *large, sparse* vector fields.

The dense condensation of ``_collocation.py`` costs :math:`O(N (mn)^3)` per linearisation: at n = 433 states and
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
   that are not small.  Along a branch the last point's leading Floquet subspace preconditions it
   (:class:`._sweeps.NewtonPicard`), which takes about half of those iterations away on the GFB.
3. **Floquet multipliers** are the leading eigenvalues of M (:class:`._floquet.BlockKrylov`: block sweeps, one
   right-hand side per column).  Only the largest in modulus are computed: they decide stability, and the rest
   are below any bifurcation's reach.

Per linearisation the cost is N sparse LU factorisations of size mn plus a few tens of sweeps, all linear in N.
Newton itself is the one corrector of :mod:`._newton`, stepped from the host (``solve_host``); this module
supplies its linearisation, and the transposed solve (:meth:`_Linearisation.solve_transpose`) for adjoint gradients.
Two economies in the correction (:meth:`SparseCollocation.correct`, settings of :class:`~._linear.SparseSweep`):
chord steps on the last factorisations while the residual keeps falling fast (``chord``), and step solves to a
loose GMRES tolerance (``gmres_forcing``); the converged orbit always gets its own linearisation, so the tangent
and the multipliers are exact there.  The blocks' fill-reducing column order is computed once per solver (every
block has the same pattern).
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

from . import _collocation as col
from ._linear import BoundSolver
from ._results import Outcome
from ._newton import LinearSolveError, NewtonSettings, NewtonSolution, solve_host
from ._sparsity import Coloring, check_pattern, color_pattern, jacobian_values
from ._sweeps import IntervalSweeps, NewtonPicard


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


_residual = jax.jit(col.residual, static_argnums=(0, 4))
_coeffs = jax.jit(col.functional_coeffs, static_argnums=(2,))
_COLORINGS: dict[tuple[int, str], Coloring] = {}  # one colouring (and one compiled kernel) per pattern


def _max_abs(*arrays) -> float:
    return float(max(np.max(np.abs(np.asarray(a))) for a in arrays))


def _sparse_linearisation(o: "SparseCollocation", orbit: col.Orbit, con: col.Constraint) -> IntervalSweeps:
    """Factorised sparse interval blocks at ``orbit`` with the rows of ``con``.  The first one checks the pattern
    against df/dx at two states of the orbit (:func:`._sparsity.check_pattern`): ValueError when it misses an
    entry."""
    if not o.pattern_checked:
        for x in (orbit.xm[0], orbit.xm[orbit.N // 2]):
            check_pattern(o.problem.f, x, orbit.lam, o.problem.args, o.coloring, "CycleProblem.jac_sparsity")
        o.pattern_checked = True
    Kd, ALd, Bp = (np.asarray(a) for a in _linear_data(o.problem.f, o.problem.args, orbit, o.scheme, o._key,
                                                       o._Kperm, o._isdiag))
    mn, n = o.scheme.m * o.n, o.n
    AL = [sps.csr_matrix((ALd[j], o._AL_indices, o._AL_indptr), shape=(mn, n)) for j in range(Kd.shape[0])]
    coef, cp, _ = _coeffs(orbit, con, o.scheme)
    return IntervalSweeps(orbit, o.scheme.m, o._factorise_all(Kd), AL, Bp, np.asarray(coef), np.asarray(cp),
                          o.settings)


class _PermutedLU:
    """SuperLU of K P, a column order P fixed in advance (``lu`` orders nothing itself), given as the compressed
    columns of K P; ``inverse``: P's inverse permutation.  The ``solve(b, trans)`` of K itself."""

    def __init__(self, KP: sps.csc_matrix, order: np.ndarray, inverse: np.ndarray):
        self.lu, self.order, self.inverse = spla.splu(KP, permc_spec="NATURAL"), order, inverse

    def solve(self, b: np.ndarray, trans: str = "N") -> np.ndarray:
        if trans == "T":  # (K P)^T z = P^T b
            return self.lu.solve(b[self.order], trans="T")
        return self.lu.solve(b)[self.inverse]  # K P y = b, x = P y


class SparseCollocation(BoundSolver):
    """The sparse linear solver bound to one problem (with ``jac_sparsity``) and scheme; see the module
    docstring.  ``settings`` is the :class:`~._linear.SparseSweep` that made it."""

    def __init__(self, problem: Any, scheme: col.Scheme, settings: Any):
        pattern = np.asarray(problem.jac_sparsity, bool)
        n = problem.n
        self.problem, self.scheme, self.settings, self.n = problem, scheme, settings, n
        self._key = (n, hashlib.sha1(np.packbits(pattern).tobytes()).hexdigest())
        if self._key not in _COLORINGS:
            _COLORINGS[self._key] = color_pattern(pattern)
        self.coloring = _COLORINGS[self._key]
        self.pattern_checked = False  # against df/dx, on the first linearisation
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
        self._order: tuple[np.ndarray, np.ndarray] | None = None  # column order of the blocks, from the first
        self._KP: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # K[:, order]: value take, pattern

    def _factorise_all(self, Kd: np.ndarray) -> list:
        """SuperLU factorisations of the interval blocks whose compressed-column values are the rows of Kd.

        Every block of every orbit has the same pattern, so the fill-reducing column order (``permc_spec``) is
        computed once, from the first block the solver sees, and given to the rest as a permutation of their
        values (a fifth of the factorisation time on the GFB), not by indexing each block's columns (0.5 ms a
        block there).

        Serial on purpose: two threads factorised large random blocks (2.3 M nonzeros in L+U) 1.6x faster on 2
        cores, but the reference grid's blocks (169,000 nonzeros, 5-6 ms each) not at all inside the branch's
        process (a linearisation 190 ms against 182 ms), and the timed reference branch took 97 s against 77 s
        for the serial code (benchmarks/README.md, cycle_branch.py)."""
        mn = self.scheme.m * self.n
        lus = []
        if self._order is None:
            K = sps.csc_matrix((Kd[0], self._K_indices, self._K_indptr), shape=(mn, mn))
            try:
                lu = spla.splu(K, permc_spec=self.settings.permc_spec)
            except RuntimeError as e:  # "Factor is exactly singular"
                raise LinearSolveError(f"collocation block of interval 0 is singular: {e}") from e
            position = np.asarray(lu.perm_c)  # SuperLU's perm_c: where each column of K goes
            cols = np.empty_like(position)
            cols[position] = np.arange(len(position))  # the columns of K in factorisation order
            self._order = (cols, position)
            # the values of K[:, cols] in compressed-column order, taken from those of K, and its pattern
            starts, ends = self._K_indptr[cols], self._K_indptr[cols + 1]
            take = np.concatenate([np.arange(a, b) for a, b in zip(starts, ends)])
            self._KP = (take, self._K_indices[take],
                        np.concatenate([[0], np.cumsum(ends - starts)]).astype(np.int32))
            lus.append(lu)
        take, indices, indptr = self._KP
        for j in range(len(lus), len(Kd)):
            try:
                lus.append(_PermutedLU(sps.csc_matrix((Kd[j][take], indices, indptr), shape=(mn, mn)),
                                       *self._order))
            except RuntimeError as e:  # "Factor is exactly singular"
                raise LinearSolveError(f"collocation block of interval {j} is singular: {e}") from e
        return lus

    def linearise(self, orbit: col.Orbit, con: col.Constraint | None = None) -> IntervalSweeps:
        return _sparse_linearisation(self, orbit, con if con is not None else col.natural_constraint(orbit,
                                                                                                     orbit.lam))

    def correct(self, orbit: col.Orbit, con: col.Constraint, newton: NewtonSettings,
                subspace: np.ndarray | None = None) -> tuple[NewtonSolution, IntervalSweeps | None]:
        """Newton on the host: each evaluation factorises at the iterate and solves for the step; the converged
        point keeps its linearisation, which gives the tangent (one more GMRES solve) and later the multipliers.
        ``subspace``: an orthonormal basis (n, c) of the leading Floquet subspace of a nearby orbit (the last
        point's); with ``settings.deflate`` it preconditions every GMRES solve of the correction
        (:class:`~._sweeps.NewtonPicard`, built once, on the first linearisation)."""
        N, m, n = orbit.N, self.scheme.m, self.n
        f, args = self.problem.f, self.problem.args

        chord = self.settings.chord if newton.verify_residual else 0.0
        # the factorisations a chord step may reuse, the last residual, the evaluations so far, and the
        # preconditioner (None: not built yet; False: none to build)
        made = {"lin": None, "last": np.inf, "calls": 0,
                "pc": None if self.settings.deflate and subspace is not None else False}

        def fresh(o):
            lin = self.linearise(o, con)
            if made["pc"] is None:
                made["pc"] = NewtonPicard.build(lin, subspace) or False
            lin.preconditioner = made["pc"] or None
            return lin

        def linearise(o, accepts):
            rc, rper, rs = (np.asarray(a) for a in _residual(f, args, o, con, self.scheme))
            rnorm = _max_abs(rc, rper, rs)
            if not np.isfinite(rnorm):  # ends the iteration as NONFINITE without a factorisation
                return rnorm, col.Orbit(jnp.zeros_like(o.mesh), o.xm * np.nan, o.xi, o.T, o.lam), None
            if accepts(rnorm):  # converged here: the linearisation at this orbit gives the tangent, no step
                lin = fresh(o)
                return rnorm, col.Orbit(jnp.zeros_like(o.mesh), jnp.zeros_like(o.xm), jnp.zeros_like(o.xi),
                                        jnp.zeros_like(o.T), jnp.zeros_like(o.lam)), lin
            # chord step: while the last step cut the residual by the factor ``chord`` or more, the old
            # factorisations still give a step that converges fast (the Jacobian moved by about the correction
            # so far); a slower step (a linear rate that would need many steps) gets new ones.  Only the
            # converged orbit needs its own (for the tangent and the multipliers).
            lin, last = made["lin"], made["last"]
            made["calls"] += 1
            # inexact Newton: the step's GMRES need only be as accurate as the residual it removes (forcing term
            # of Dembo, Eisenstat and Steihaug, proportional to the residual: the convergence stays quadratic);
            # a chord step converges only linearly, at the rate just seen, and a tenth of that rate is enough
            rtol = min(self.settings.gmres_forcing, rnorm)
            # the last two steps of the iteration budget are full Newton steps: a slow solve from a poor guess
            # must not run out of iterations because of a chord step that exact Newton would not have taken
            if lin is None or not rnorm <= chord * last or made["calls"] >= newton.max_iter - 1:
                lin = fresh(o)
                made["lin"] = lin
            else:
                rtol = min(self.settings.gmres_forcing, max(rtol, 0.1 * rnorm / last))
            made["last"] = rnorm
            d = lin.solve(-rc, -rper, -rs, rtol=max(self.settings.gmres_rtol, rtol))
            return rnorm, col.Orbit(jnp.zeros_like(o.mesh), d.xm, d.xi, d.T, d.lam), lin

        sol = solve_host(linearise, orbit, newton, scale=lambda o: jnp.max(jnp.abs(o.xm)), knows_acceptance=True)
        if not sol.converged:
            return sol, None
        lin = sol.aux
        try:
            t = lin.solve(np.zeros((N, m, n)), np.zeros(n), np.array([0.0, 1.0]))
        except LinearSolveError:
            return NewtonSolution(sol.x, None, Outcome.LINEAR_SOLVE_FAILED.code, sol.iterations, sol.residual,
                                  sol.step), None
        t = t.scale(1.0 / float(jnp.sqrt(col.inner(t, t, self.scheme))))
        return NewtonSolution(sol.x, t, sol.code, sol.iterations, sol.residual, sol.step), lin
