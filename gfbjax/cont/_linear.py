r"""Linear solvers for the bordered collocation Newton system, behind one protocol.

The Newton system of the periodic BVP (27)-(30) (see :mod:`._collocation`) is

.. math:: J\,\delta = r,\qquad J = \begin{bmatrix} L_{coll} & B_p\\ I\ \cdots\ -I & 0\\ \phi^T & \psi^T
          \end{bmatrix}

(collocation rows, periodicity, phase and continuation rows).  A solver is chosen by a small settings object
(:class:`DenseCondensation`, :class:`SparseSweep`), *bound* to a problem and a collocation scheme
(``solver.bind(problem, scheme)``), and the bound solver gives

* ``correct(orbit, con, newton)``: the Newton correction of ``orbit`` (the one corrector of :mod:`._newton`),
  returning the solution with the normalised tangent, and the :class:`Linearisation` at the converged orbit;
* ``linearise(orbit, con)``: a :class:`Linearisation`.

A linearisation at one orbit provides ``solve`` (:math:`J^{-1}r`), ``solve_transpose`` (:math:`J^{-T}g`, for
adjoint gradients), the transfer matrices :math:`\Gamma_j` and the monodromy operator :math:`M` and its transpose
(for Floquet multipliers, see :mod:`._floquet`).

*Dense condensation* (AUTO's condensation of parameters, batched dense QR per interval, then a block elimination;
everything compiled, one kernel per Newton solve): all n multipliers; cost :math:`O(N (mn)^3)`, for n up to ~150.
*Sparse sweep* (per-interval SuperLU factorisations of the sparse collocation blocks, GMRES on the (n+2) reduced
system, on the host; :mod:`._sparse`): the leading multipliers by a block Krylov method; cost linear in N and
close to linear in n for banded Jacobians, for large n.
"""
from __future__ import annotations

import abc
from dataclasses import dataclass
from functools import partial
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from . import _collocation as col
from ._checks import store_range
from ._newton import NewtonSettings, NewtonSolution, solve as newton_solve
from ._problem import CycleProblem

__all__ = ["LinearSolver", "DenseCondensation", "SparseSweep", "Linearisation", "BoundSolver", "choose_solver",
           "SPARSE_MIN_N"]

#: Below this state count the "auto" choice is the dense condensation (sparse is ~8x faster per Newton solve at
#: n = 102 and slower below ~60).
SPARSE_MIN_N = 80


class Linearisation(abc.ABC):
    """The collocation Jacobian at one orbit (with the phase/continuation rows of a constraint)."""

    orbit: col.Orbit

    @abc.abstractmethod
    def solve(self, rc: Any, rper: Any, rs: Any) -> col.Orbit:
        """J^{-1} (rc (N, m, n), rper (n,), rs (2,)), orbit-shaped."""

    @abc.abstractmethod
    def solve_transpose(self, g: col.Orbit) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """J^{-T} g for g orbit-shaped (a gradient with respect to the unknowns): the multipliers of the
        collocation rows (N, m, n), of the periodicity rows (n,) and of the two scalar rows (2,)."""

    @abc.abstractmethod
    def transfer_matrices(self) -> np.ndarray:
        """Gamma_j (N, n, n): the linearised map x_j -> x_{j+1} at fixed T, lam."""

    @abc.abstractmethod
    def default_floquet(self) -> Any:
        """The Floquet method that suits this linearisation (all multipliers when dense, the leading ones by
        Arnoldi otherwise)."""

    @abc.abstractmethod
    def monodromy_matvec(self, v: np.ndarray) -> np.ndarray:
        """M v (M = Gamma_{N-1} ... Gamma_0)."""

    @abc.abstractmethod
    def monodromy_rmatvec(self, y: np.ndarray) -> np.ndarray:
        """M^T y."""

    def host_solve(self, rc: Any, rper: Any, rs: Any) -> col.Orbit:
        """J^{-1} (rc, rper, rs) like :meth:`solve`, by the interval factorisations on the host where the
        linearisation has them (no compilation for a new shape: the a-posteriori estimates' solves)."""
        return self.solve(rc, rper, rs)

    def monodromy_matmat(self, V: np.ndarray) -> np.ndarray:
        """M V for a block V (n, b); column by column unless a linearisation can do better."""
        V = np.asarray(V, float)
        return np.stack([self.monodromy_matvec(V[:, i]) for i in range(V.shape[1])], axis=1)

    @abc.abstractmethod
    def sweep(self, dx0: np.ndarray, dp: np.ndarray, c: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The linearised orbit (mesh values (N+1, n), interior values (N, m-1, n)) from (dx0, dp) with
        collocation right-hand sides c (N, mn) (see :mod:`._sweeps`); a block dx0 (n, b) with dp = 0 and c
        (N, mn, b) gives b orbits, (N+1, n, b) and (N, m-1, n, b)."""

    @abc.abstractmethod
    def local_solves(self, c: np.ndarray) -> np.ndarray:
        """Interior values (N, m-1, n) of the linearised orbit on each interval alone, from a zero left mesh
        value at fixed (T, lam), with collocation right-hand sides c (N, mn): one block solve per interval."""

    @abc.abstractmethod
    def adjoint_sweep(self, w: np.ndarray) -> np.ndarray:
        """psi (N, mn) with sum_j psi_j . c_j = w . x_N for the sweep from 0 with right-hand sides c."""

    @abc.abstractmethod
    def solve_many(self, rc: Any) -> list[col.Orbit]:
        """J^{-1} (rc[i], 0, 0) for a stack of collocation right-hand sides rc (k, N, m, n)."""


class BoundSolver(abc.ABC):
    """A linear solver bound to one problem and scheme."""

    problem: CycleProblem
    scheme: col.Scheme

    @abc.abstractmethod
    def correct(self, orbit: col.Orbit, con: col.Constraint, newton: NewtonSettings,
                subspace: np.ndarray | None = None) -> tuple[NewtonSolution, Linearisation | None]:
        """Newton correction; the solution's ``aux`` is the normalised tangent (continuation row of ``con`` fixes
        its orientation); the linearisation is at the converged orbit (None when not converged).  ``subspace``:
        an orthonormal basis (n, c) of the leading Floquet subspace of a nearby orbit, a hint a solver may use
        to precondition its solves (the result does not depend on it)."""

    @abc.abstractmethod
    def linearise(self, orbit: col.Orbit, con: col.Constraint | None = None) -> Linearisation:
        """The Jacobian at ``orbit``; ``con`` defaults to fixed lam with phase reference ``orbit``."""


class LinearSolver(abc.ABC):
    """Settings of a linear solver; :meth:`bind` makes the solver for one problem."""

    name: str = ""

    @abc.abstractmethod
    def bind(self, problem: CycleProblem, scheme: col.Scheme) -> BoundSolver: ...



# ---------------------------------------------------------------- dense condensation
def _mesh_scale(o: col.Orbit) -> jax.Array:
    return jnp.max(jnp.abs(o.xm))


def dense_linearise_step(f, args, orbit: col.Orbit, con: col.Constraint, scheme: col.Scheme):
    """``linearise`` for the Newton corrector: (residual max-norm, step with zero mesh, tangent)."""
    new, rnorm, _, tan = col.step_and_tangent(f, args, orbit, con, scheme)
    d = col.Orbit(jnp.zeros_like(orbit.mesh), new.xm - orbit.xm, new.xi - orbit.xi, new.T - orbit.T,
                  new.lam - orbit.lam)
    return rnorm, d, tan


def dense_correct(f, args, orbit: col.Orbit, con: col.Constraint, scheme: col.Scheme,
                  newton: NewtonSettings) -> NewtonSolution:
    """The dense Newton correction as pure JAX (jit it, or ``jax.vmap`` it over ``args``).  The step has a zero
    mesh component (the mesh is data, not an unknown), and the step test is relative to the mesh values."""
    return newton_solve(lambda o: dense_linearise_step(f, args, o, con, scheme), orbit, newton, scale=_mesh_scale)


_dense_correct = jax.jit(dense_correct, static_argnums=(0, 4, 5))
_transfer = jax.jit(col.transfer_matrices, static_argnums=(0, 3))
_solve_multi = jax.jit(col.linear_solve_multi, static_argnums=(0, 4))
_blocks = jax.jit(col.collocation_blocks, static_argnums=(0, 3))
_coeffs = jax.jit(col.functional_coeffs, static_argnums=(2,))


@partial(jax.jit, static_argnums=(0, 4))
def _dense_transpose(f, args, orbit, con, scheme, gxm, gxi, gp):
    z = orbit.xm.dtype

    def solve(rc, rper, rs):  # J^{-1}, linear in the right-hand side
        dxm, dw, dp = col.linear_solve_multi(f, args, orbit, con, scheme, rc[..., None], rper[:, None],
                                             rs[:, None])
        return dxm[..., 0], dw[..., 0], dp[:, 0]

    zeros = (jnp.zeros((orbit.N, scheme.m, orbit.n), z), jnp.zeros((orbit.n,), z), jnp.zeros((2,), z))
    return jax.vjp(solve, *zeros)[1]((gxm, gxi, gp))


class _DenseLinearisation(Linearisation):
    def __init__(self, bound: "_DenseBound", orbit: col.Orbit, con: col.Constraint):
        self.bound, self.orbit, self.con = bound, orbit, con
        self._G: np.ndarray | None = None
        self._sw = None

    def _args(self):
        return self.bound.problem.f, self.bound.problem.args

    def solve(self, rc, rper, rs) -> col.Orbit:
        f, args = self._args()
        dxm, dw, dp = _solve_multi(f, args, self.orbit, self.con, self.bound.scheme, jnp.asarray(rc)[..., None],
                                   jnp.asarray(rper)[:, None], jnp.asarray(rs)[:, None])
        return col.Orbit(self.orbit.mesh, dxm[..., 0], dw[..., 0], dp[0, 0], dp[1, 0])

    def solve_many(self, rc: Any) -> list[col.Orbit]:
        """J^{-1} (rc[i], 0, 0) for a stack of collocation right-hand sides rc (k, N, m, n): one factorisation."""
        f, args = self._args()
        rc = jnp.moveaxis(jnp.asarray(rc), 0, -1)
        k, n = rc.shape[-1], self.orbit.n
        dxm, dw, dp = _solve_multi(f, args, self.orbit, self.con, self.bound.scheme, rc, jnp.zeros((n, k)),
                                   jnp.zeros((2, k)))
        return [col.Orbit(self.orbit.mesh, dxm[..., i], dw[..., i], dp[0, i], dp[1, i]) for i in range(k)]

    def solve_transpose(self, g: col.Orbit):
        f, args = self._args()
        out = _dense_transpose(f, args, self.orbit, self.con, self.bound.scheme, g.xm, g.xi,
                               jnp.stack([g.T, g.lam]))
        return tuple(np.asarray(a) for a in out)

    def transfer_matrices(self) -> np.ndarray:
        if self._G is None:
            f, args = self._args()
            self._G = np.asarray(_transfer(f, args, self.orbit, self.bound.scheme))
        return self._G

    def monodromy_matvec(self, v):
        for g in self.transfer_matrices():
            v = g @ v
        return v

    def monodromy_rmatvec(self, y):
        for g in self.transfer_matrices()[::-1]:
            y = g.T @ y
        return y

    def default_floquet(self):
        from ._floquet import PeriodicQR
        return PeriodicQR()

    def _sweeps(self):
        """The same Jacobian as interval sweeps with dense LU per interval (for derivative computations)."""
        if self._sw is None:
            from ._sweeps import DenseLU, IntervalSweeps
            f, args = self._args()
            AL, AI, AR, Bp = (np.asarray(a) for a in _blocks(f, args, self.orbit, self.bound.scheme))
            coef, cp, _ = _coeffs(self.orbit, self.con, self.bound.scheme)
            lus = [DenseLU(np.concatenate([ai, ar], axis=1)) for ai, ar in zip(AI, AR)]
            self._sw = IntervalSweeps(self.orbit, self.bound.scheme.m, lus, list(AL), Bp, np.asarray(coef),
                                      np.asarray(cp), SparseSweep(), direct=True)
        return self._sw

    def host_solve(self, rc, rper, rs) -> col.Orbit:
        return self._sweeps().solve(rc, rper, rs)

    def sweep(self, dx0, dp, c=None):
        return self._sweeps().sweep(dx0, dp, c)

    def local_solves(self, c):
        return self._sweeps().local_solves(c)

    def adjoint_sweep(self, w):
        return self._sweeps().adjoint_sweep(w)


class _DenseBound(BoundSolver):
    def __init__(self, problem: CycleProblem, scheme: col.Scheme):
        self.problem, self.scheme = problem, scheme

    def correct(self, orbit, con, newton, subspace=None):  # direct solves: nothing to precondition
        sol = _dense_correct(self.problem.f, self.problem.args, orbit, con, self.scheme, newton)
        if not sol.converged:
            return sol, None
        return sol, _DenseLinearisation(self, sol.x, con)

    def linearise(self, orbit, con=None):
        return _DenseLinearisation(self, orbit, con if con is not None else col.natural_constraint(orbit, orbit.lam))


@dataclass(frozen=True)
class DenseCondensation(LinearSolver):
    """Dense condensation of parameters (all n Floquet multipliers available); for n up to ~150."""

    name = "dense"

    def bind(self, problem, scheme) -> BoundSolver:
        return _DenseBound(problem, scheme)


@dataclass(frozen=True)
class SparseSweep(LinearSolver):
    """Per-interval sparse LU + GMRES on the reduced system + block Krylov multipliers (needs
    ``CycleProblem.jac_sparsity``).  gmres_rtol: relative GMRES tolerance of each solve (the Newton test on the
    true residual decides convergence); gmres_restart, gmres_maxiter: GMRES restart length and restarts (the
    reduced system has n + 2 unknowns and its spectrum clusters at 1: 15-30 iterations suffice on the GFB, and
    where more are needed the system is nearly singular, next to a branch point, and more restarts only delay
    the failure that halves the step: 20 restarts made the Brusselator branch 2.8x slower there);
    gmres_forcing: the loosest relative tolerance of a Newton step's GMRES solve, which is solved to
    max(gmres_rtol, min(gmres_forcing, residual)) (inexact Newton; tangents and other solves use gmres_rtol);
    chord: a Newton step reuses the last factorisations while each step cuts the residual by at least this factor
    (residual <= chord * previous residual; 0: a new factorisation at every step); the converged orbit always
    gets its own;
    permc_spec: SuperLU column ordering;
    deflate: precondition the GMRES solves of a correction by the leading Floquet subspace of the last point of the
    branch (Newton-Picard, :class:`~._sweeps.NewtonPicard`): the same solutions in fewer sweeps."""

    name = "sparse"
    gmres_rtol: float = 1e-11
    gmres_restart: int = 120
    gmres_maxiter: int = 4
    gmres_forcing: float = 1e-3
    chord: float = 1e-2
    permc_spec: str = "COLAMD"
    deflate: bool = True

    def __post_init__(self) -> None:
        put = partial(store_range, self)
        put("gmres_rtol", 0.0, 1.0, lo_open=True, hi_open=True)
        put("gmres_forcing", self.gmres_rtol, 1.0, hi_open=True)
        put("chord", 0.0, 1.0, hi_open=True)
        put("gmres_restart", 1, 10**6, integer=True)
        put("gmres_maxiter", 1, 10**6, integer=True)
        if not isinstance(self.deflate, bool):
            raise ValueError(f"deflate must be True or False, got {self.deflate!r}")
        if self.permc_spec not in ("COLAMD", "NATURAL", "MMD_ATA", "MMD_AT_PLUS_A"):
            raise ValueError(f"permc_spec must be one of COLAMD, NATURAL, MMD_ATA, MMD_AT_PLUS_A, "
                             f"got {self.permc_spec!r}")

    def bind(self, problem, scheme) -> BoundSolver:
        if problem.jac_sparsity is None:
            raise ValueError("the sparse linear solver needs CycleProblem.jac_sparsity (the pattern of df/dx)")
        from ._sparse import SparseCollocation
        return SparseCollocation(problem, scheme, self)


def choose_solver(solver: LinearSolver | None, problem: CycleProblem) -> LinearSolver:
    """``solver``, or the automatic choice: sparse when the problem has a Jacobian pattern and n >= SPARSE_MIN_N."""
    if solver is not None:
        if not isinstance(solver, LinearSolver):
            raise ValueError(f"linear_solver must be DenseCondensation(), SparseSweep(...) or None (automatic), "
                             f"got {solver!r}")
        return solver
    if problem.jac_sparsity is not None and problem.n >= SPARSE_MIN_N:
        return SparseSweep()
    return DenseCondensation()
