r"""The collocation Jacobian as interval sweeps: one linearisation class for factorised interval blocks.

On interval j, with the left mesh value :math:`x_j` given, the m collocation equations determine the m node blocks
:math:`z_j = (w_j, x_{j+1})`:

.. math:: K_j z_j = c_j - A_{L,j} x_j - B_{p,j}\,\delta p,\qquad K_j = [A_I\ A_R].

A *sweep* over j = 0..N-1 maps :math:`(x_0, \delta p)` to the whole linearised orbit (multiple shooting with
implicit collocation steps); the *adjoint sweep* runs the transposed blocks from the last interval back.  On top
of the two:

* :meth:`IntervalSweeps.solve`: the bordered Newton system, reduced to the n + 2 unknowns :math:`(x_0, \delta p)`
  (periodicity, phase and continuation rows) and solved by GMRES whose product is one sweep;
* :meth:`IntervalSweeps.solve_transpose`: :math:`J^T\lambda = g` the same way with adjoint sweeps;
* the monodromy operator :math:`M = \Gamma_{N-1}\cdots\Gamma_0` and its transpose, and the transfer matrices;
* :class:`NewtonPicard`: a preconditioner of :meth:`IntervalSweeps.solve`'s GMRES from a leading Floquet
  subspace.

The factorisations may be SuperLU objects (sparse blocks, :mod:`._sparse`) or dense LU (:class:`DenseLU`, for
the derivative computations of the dense solver): anything with ``solve(b, trans="N"|"T")``.
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import jax.numpy as jnp
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from . import _collocation as col
from ._linear import Linearisation
from ._newton import LinearSolveError

__all__ = ["IntervalSweeps", "DenseLU", "NewtonPicard"]


class DenseLU:
    """A dense LU with the ``solve(b, trans)`` interface of SuperLU.

    The solve calls LAPACK's getrs as ``scipy.linalg.lu_solve`` does, without its argument handling: at small n a
    branch makes ~200 interval solves per point of a few microseconds each, and lu_solve's checks took 20 us a
    call (16 % of a point at n = 4)."""

    def __init__(self, K: np.ndarray):
        self._lu, self._piv = sla.lu_factor(K, check_finite=False)

    def solve(self, b: np.ndarray, trans: str = "N") -> np.ndarray:
        getrs = _GETRS if self._lu.dtype.char == b.dtype.char == "d" else sla.get_lapack_funcs("getrs", (self._lu, b))
        x, info = getrs(self._lu, self._piv, b, trans=1 if trans == "T" else 0)
        if info:  # only for bad arguments (getrs does not test for singularity), as in lu_solve
            raise ValueError(f"illegal value in argument {-info} of getrs")
        return x


# getrs for float64 factors and right-hand sides; any other pair goes through get_lapack_funcs, which picks the
# routine for both dtypes (a real one would drop a complex factor's imaginary part)
_GETRS = sla.get_lapack_funcs("getrs", (np.zeros((1, 1)),))


class IntervalSweeps(Linearisation):
    """Factorised interval blocks at one orbit, with the phase/continuation rows of one constraint.

    orbit: the linearisation point; m: collocation degree; lus: N factorisations of K_j (mn x mn); AL: N blocks
    A_{L,j} (mn x n, anything with ``@`` and ``.T``); Bp: (N, mn, 2) columns d/dT, d/dlam; coef (2, N, m+1, n) and
    cp (2, 2): the two scalar rows on the nodes and on (T, lam); gmres: settings with ``gmres_rtol``,
    ``gmres_restart``, ``gmres_maxiter``; direct: :meth:`solve` factorises the reduced system instead (small n).
    """

    def __init__(self, orbit: col.Orbit, m: int, lus: Sequence[Any], AL: Sequence[Any], Bp: np.ndarray,
                 coef: np.ndarray, cp: np.ndarray, gmres: Any, direct: bool = False):
        self.orbit, self.m, self.n = orbit, m, orbit.n
        self.lus, self.AL, self.Bp, self.coef, self.cp, self.gmres = list(lus), list(AL), Bp, coef, cp, gmres
        # direct: the reduced (n + 2) system is formed by one block sweep and factorised, not solved by GMRES (for
        # small n, where n + 2 sweep columns cost less than a GMRES solve and need no tolerance)
        self.direct, self._reduced = direct, None
        #: A preconditioner of the reduced system for GMRES (:class:`NewtonPicard`), or None.
        self.preconditioner: NewtonPicard | None = None

    # ---- sweeps
    def sweep(self, dx0: np.ndarray, dp: np.ndarray, c: np.ndarray | None = None):
        """Mesh values (N+1, n) and interior values (N, m-1, n) of the linearised orbit from (dx0, dp), with
        collocation right-hand sides ``c`` (N, mn) (default 0).  A block dx0 (n, b) with dp = 0 and c (N, mn, b)
        sweeps b orbits at once (each factor read once for the block): (N+1, n, b) and (N, m-1, n, b)."""
        N, k = len(self.lus), (self.m - 1) * self.n
        dx0 = np.asarray(dx0)
        block = dx0.shape[1:]
        move_p = bool(np.any(dp))  # a homogeneous sweep (M v, Arnoldi) skips the parameter columns
        if block and move_p:
            raise ValueError("a block sweep moves no parameter: dp must be 0")
        xs = np.empty((N + 1, self.n) + block)
        ws = np.empty((N, k) + block)
        xs[0] = x = dx0
        for j, lu in enumerate(self.lus):
            rhs = self.AL[j] @ x
            if move_p:
                rhs += self.Bp[j] @ dp
            if c is not None:
                rhs -= c[j]
            z = lu.solve(-rhs)
            ws[j] = z[:k]
            xs[j + 1] = x = z[k:]
        return xs, ws.reshape((N, self.m - 1, self.n) + block)

    def local_solves(self, c: np.ndarray) -> np.ndarray:
        k = (self.m - 1) * self.n
        return np.stack([lu.solve(cj)[:k] for lu, cj in zip(self.lus, c)]).reshape(len(self.lus), self.m - 1,
                                                                                   self.n)

    def adjoint_sweep(self, w: np.ndarray) -> np.ndarray:
        """psi (N, mn) with sum_j psi_j . c_j = w . x_N for the sweep from x_0 = 0, dp = 0 with right-hand sides c:
        the transposed blocks from the last interval back (M^T w is then -A_{L,0}^T psi_0)."""
        k = (self.m - 1) * self.n
        psis = [None] * len(self.lus)
        y = np.asarray(w)
        for j in range(len(self.lus) - 1, -1, -1):
            psis[j] = self.lus[j].solve(np.concatenate([np.zeros(k, dtype=y.dtype), y]), trans="T")
            y = -(self.AL[j].T @ psis[j])
        return np.array(psis)

    def sweep_transpose(self, lam_per: np.ndarray, lam_s: np.ndarray, gxm=None, gxi=None, gp=None):
        """Multipliers of the collocation rows (N, mn) from those of the periodicity (lam_per) and scalar rows
        (lam_s), and the residual (n + 2,) of the remaining transposed equations (columns of x_0 and (T, lam)),
        for the right-hand side g = (gxm, gxi, gp) (default 0).  See :meth:`solve_transpose`."""
        N, m, n = len(self.lus), self.m, self.n
        C = np.einsum("a,ajin->jin", lam_s, self.coef)  # the scalar rows' weight on every node, (N, m+1, n)
        bx = np.zeros((N + 1, n))
        bx[:-1] += C[:, 0]
        bx[1:] += C[:, m]
        bw = C[:, 1:m]
        gxm = np.zeros((N + 1, n)) if gxm is None else gxm
        gxi = np.zeros((N, m - 1, n)) if gxi is None else gxi
        gp = np.zeros(2) if gp is None else gp
        lams = [None] * N
        nxt = lam_per  # weight on x_{j+1} from the right: +lam_per for x_N (row x_0 - x_N), then -A_L^T lam_{j+1}
        for j in range(N - 1, -1, -1):
            rhs = np.concatenate([(gxi[j] - bw[j]).ravel(), gxm[j + 1] - bx[j + 1] + nxt])
            lams[j] = self.lus[j].solve(rhs, trans="T")
            nxt = -(self.AL[j].T @ lams[j])
        r_x0 = -nxt + lam_per + bx[0] - gxm[0]  # A_L0^T lam_0 + lam_per + B_x0^T lam_s - g_x0
        r_p = sum(self.Bp[j].T @ lams[j] for j in range(N)) + self.cp.T @ lam_s - gp
        return np.array(lams), np.concatenate([r_x0, r_p])

    def _border(self, xm: np.ndarray, w: np.ndarray, dp: np.ndarray) -> np.ndarray:
        U = np.concatenate([xm[:-1, None], w, xm[1:, None]], axis=1)
        return np.einsum("ajin,jin...->a...", self.coef, U) + self.cp @ dp

    def _reduced_lu(self):
        """The LU factors of the reduced system's matrix (n + 2, n + 2) (the operator of :meth:`solve`'s GMRES):
        the x_0 columns from one block sweep of the identity, the (T, lam) columns from one sweep each."""
        if self._reduced is None:
            n = self.n
            xm, w = self.sweep(np.eye(n), np.zeros(2))
            cols = [np.concatenate([np.eye(n) - xm[-1], self._border(xm, w, np.zeros((2, n)))])]
            for k in range(2):
                dp = np.eye(2)[k]
                xk, wk = self.sweep(np.zeros(n), dp)
                cols.append(np.concatenate([-xk[-1], self._border(xk, wk, dp)])[:, None])
            self._reduced = sla.lu_factor(np.concatenate(cols, axis=1), check_finite=False)
        return self._reduced

    def _gmres(self, matvec, b: np.ndarray, rtol: float | None = None) -> np.ndarray:
        s = self.gmres
        n2 = len(b)
        if float(np.linalg.norm(b)) == 0.0:
            return np.zeros(n2)
        A = spla.LinearOperator((n2, n2), matvec=matvec, dtype=float)
        v, info = spla.gmres(A, b, rtol=s.gmres_rtol if rtol is None else rtol, atol=0.0,
                             restart=min(n2, s.gmres_restart),
                             maxiter=s.gmres_maxiter)
        if info != 0 or not np.all(np.isfinite(v)):
            raise LinearSolveError(f"GMRES did not converge (info={info})")
        return v

    # ---- the Linearisation protocol
    def solve(self, rc, rper, rs, rtol: float | None = None) -> col.Orbit:
        """J^{-1} (rc, rper, rs); ``rtol``: GMRES's relative tolerance (default the settings' ``gmres_rtol``)."""
        n = self.n
        c = np.asarray(rc).reshape(len(self.lus), -1)
        xp, wp = self.sweep(np.zeros(n), np.zeros(2), c)
        b = np.concatenate([np.asarray(rper) + xp[-1], np.asarray(rs) - self._border(xp, wp, np.zeros(2))])

        def matvec(v):
            xm, w = self.sweep(v[:n], v[n:])
            return np.concatenate([v[:n] - xm[-1], self._border(xm, w, v[n:])])

        if self.direct:
            v = sla.lu_solve(self._reduced_lu(), b, check_finite=False)
            if not np.all(np.isfinite(v)):
                raise LinearSolveError("the reduced collocation system is singular")
        elif self.preconditioner is not None:
            # right preconditioning: GMRES's residual is that of the reduced system itself, so the tolerance
            # means the same with and without it
            pc = self.preconditioner.apply
            v = pc(self._gmres(lambda y: matvec(pc(y)), b, rtol))
        else:
            v = self._gmres(matvec, b, rtol)
        xm, w = self.sweep(v[:n], v[n:], c)
        return col.Orbit(self.orbit.mesh, jnp.asarray(xm), jnp.asarray(w), jnp.asarray(v[n]), jnp.asarray(v[n + 1]))

    def solve_many(self, rc: Any) -> list[col.Orbit]:
        """J^{-1} (rc[i], 0, 0) for a stack of collocation right-hand sides rc (k, N, m, n)."""
        n = self.n
        return [self.solve(r, np.zeros(n), np.zeros(2)) for r in np.asarray(rc)]

    def solve_transpose(self, g: col.Orbit):
        """J^T lam = g by adjoint sweeps: for given multipliers (lam_per, lam_s) of the periodicity and scalar
        rows, the columns of (w_j, x_{j+1}) give the collocation multipliers by transposed solves from the last
        interval back; the columns of x_0 and (T, lam) are n + 2 equations for (lam_per, lam_s), solved by GMRES
        (the transpose of the forward reduced system)."""
        n = self.n
        gxm, gxi, gp = np.asarray(g.xm), np.asarray(g.xi), np.array([float(g.T), float(g.lam)])
        _, r0 = self.sweep_transpose(np.zeros(n), np.zeros(2), gxm, gxi, gp)
        v = self._gmres(lambda v: self.sweep_transpose(v[:n], v[n:])[1], -r0)
        lams, _ = self.sweep_transpose(v[:n], v[n:], gxm, gxi, gp)
        return lams.reshape(len(self.lus), self.m, n), v[:n], v[n:]

    def monodromy_matvec(self, v: np.ndarray) -> np.ndarray:
        return self.sweep(np.asarray(v, float), np.zeros(2))[0][-1]

    def monodromy_matmat(self, V: np.ndarray) -> np.ndarray:
        """M V for a block V (n, b): one sweep with b right-hand sides per factorisation, which reads each factor
        from memory once for the whole block (per vector about 4x cheaper than b single sweeps at b = 16)."""
        k = (self.m - 1) * self.n
        x = np.asarray(V, float)
        for lu, AL in zip(self.lus, self.AL):
            x = lu.solve(-(AL @ x))[k:]
        return x

    def monodromy_rmatvec(self, y: np.ndarray) -> np.ndarray:
        """M^T y (M = Gamma_{N-1}...Gamma_0, Gamma_j = -E K_j^{-1} A_{L,j} with E the last n rows)."""
        return -(self.AL[0].T @ self.adjoint_sweep(np.asarray(y, float))[0])

    def default_floquet(self):
        from ._floquet import BlockKrylov
        return BlockKrylov()

    def transfer_matrices(self) -> np.ndarray:
        """Gamma_j (N, n, n) (n right-hand sides per interval: for branch switching, not per point)."""
        k = (self.m - 1) * self.n
        return np.array([-lu.solve(_dense(AL))[k:] for lu, AL in zip(self.lus, self.AL)])


class NewtonPicard:
    r"""Preconditioner of the reduced system :math:`A = [I - M,\ G;\ \Phi,\ \Psi]` (unknowns
    :math:`(\delta x_0, \delta T, \delta\lambda)`, see :meth:`IntervalSweeps.solve`) from an orthonormal basis V
    (n, c) of the leading Floquet subspace: the monodromy matrix and the phase/continuation rows are kept on span V,
    and M is dropped on its complement,

    .. math:: P = \begin{bmatrix} I - (MV)V^T & G\\ (\Phi V) V^T & \Psi \end{bmatrix}
              = I + U Z^T,\qquad Z^T = \operatorname{diag}(V^T, I_2),

    inverted by the Sherman-Morrison-Woodbury formula with one dense (c + 2) factorisation.  This is the
    Newton-Picard splitting of Lust, Roose, Spence and Champneys (SIAM J. Sci. Comput. 19, 1998), used as a
    preconditioner.  The reduced operator's spectrum clusters at 1 except for the eigenvalues :math:`1 - \mu` of
    the multipliers that are not small (and the border): GMRES needs about one iteration for each.  :math:`AP^{-1}`
    has them at 1 where V spans their eigenvectors, so the iteration count falls to what the multipliers outside V
    and the phase row's part outside V still need.  V need not be exact: a subspace from a nearby orbit (the
    previous point of a branch) deflates nearly as well, and a poor one only costs iterations, never accuracy
    (right preconditioning leaves GMRES's residual that of A).

    Cost to build: one block sweep of the c columns of V and two single sweeps (the parameter columns G, Psi)."""

    def __init__(self, lin: "IntervalSweeps", V: np.ndarray):
        n, c = lin.n, V.shape[1]
        xs, ws = lin.sweep(V, np.zeros(2))
        W = xs[-1]  # M V
        PhiV = lin._border(xs, ws, np.zeros((2, c)))
        cols = []
        for k in range(2):
            dp = np.eye(2)[k]
            xk, wk = lin.sweep(np.zeros(n), dp)
            cols.append(np.concatenate([-xk[-1], lin._border(xk, wk, dp)]))
        Gcol = np.stack(cols, axis=1)  # the reduced system's (T, lam) columns, exact
        G, Psi = Gcol[:n], Gcol[n:]
        self.V = V
        self.U = np.block([[-W, G], [PhiV, Psi - np.eye(2)]])
        C = np.block([[np.eye(c) - V.T @ W, V.T @ G], [PhiV, Psi]])
        finite = bool(np.all(np.isfinite(C)) and np.all(np.isfinite(self.U)))
        self.cond = float(np.linalg.cond(C)) if finite else math.inf
        self._C = sla.lu_factor(C, check_finite=False) if np.isfinite(self.cond) else None

    @classmethod
    def build(cls, lin: "IntervalSweeps", V: np.ndarray | None) -> "NewtonPicard | None":
        """The preconditioner, or None where V does not fit (wrong state count, no columns, not finite) or the
        projected system is not finite or numerically singular (then plain GMRES is the safer choice)."""
        if V is None or V.ndim != 2 or V.shape[0] != lin.n or V.shape[1] == 0 or not np.all(np.isfinite(V)):
            return None
        pc = cls(lin, np.asarray(V, float))
        return pc if np.isfinite(pc.cond) and pc.cond < 1e10 else None

    def apply(self, y: np.ndarray) -> np.ndarray:
        """P^{-1} y for y (n + 2,)."""
        n = self.V.shape[0]
        z = np.concatenate([self.V.T @ y[:n], y[n:]])
        return y - self.U @ sla.lu_solve(self._C, z, check_finite=False)


def _dense(A: Any) -> np.ndarray:
    return A.toarray() if sps.issparse(A) else np.asarray(A)
