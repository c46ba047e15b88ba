r"""Floquet multipliers from the condensed collocation blocks.

The monodromy matrix is the product of the per-interval transfer matrices
:math:`M = \Gamma_{N-1}\cdots\Gamma_0`, :math:`\Gamma_j = -D_j^{-1}C_j` (see
``_collocation.py``).  Its eigenvalues are the Floquet multipliers; one of them
is (up to discretisation error) the trivial multiplier +1 of the autonomous
orbit.

Two methods are provided:

``multipliers_product``
    eigenvalues of the explicitly formed product.  Simple, but every entry of
    the product carries an absolute error ~ eps * ||M||, so multipliers much
    smaller than eps * max|mu| are pure round-off.

``multipliers_periodic``
    product-eigenvalue method by *periodic QR (orthogonal) iteration*.  A sweep
    factors :math:`\Gamma_j Q_j = Q_{j+1} R_j` (QR) for j = 0..N-1, so that

    .. math:: Q_0^T M Q_0 = (Q_0^T Q_N)\, R_{N-1}\cdots R_0 .

    Sweeps are repeated with :math:`Q_0 \leftarrow Q_N` (started from the Schur
    vectors of the explicit product, ordered by decreasing modulus) until
    :math:`B = Q_0^TQ_N` is block diagonal (1x1 blocks +-1, 2x2 blocks for
    complex pairs / equal moduli).  Then :math:`Q_0^TMQ_0` is quasi-triangular
    and each eigenvalue comes from a diagonal block,
    :math:`\mu_k = B_{kk}\prod_j (R_j)_{kk}`, accumulated as a sum of
    logarithms: every multiplier gets a *relative* accuracy, no matter how
    many decades the multipliers span (this is the periodic Schur idea of
    Bojanczyk/Golub/Van Dooren, realised by subspace iteration).
"""
from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from ._checks import check_range, store


def monodromy_product(G: np.ndarray) -> np.ndarray:
    """The explicitly formed product G[N-1] @ ... @ G[0] (n, n) of transfer matrices G (N, n, n)."""
    G = np.asarray(G)
    M = np.eye(G.shape[-1])
    for g in G:
        M = g @ M
    return M


def multipliers_product(G: np.ndarray) -> np.ndarray:
    """Eigenvalues of :func:`monodromy_product` (G)."""
    return np.linalg.eigvals(monodromy_product(G))


@jax.jit
def _sweep(G: jax.Array, Q0: jax.Array):
    def step(Q, g):
        Qn, R = jnp.linalg.qr(g @ Q)
        # make diag(R) >= 0 so that Q converges (not only its span)
        s = jnp.where(jnp.diagonal(R) < 0, -1.0, 1.0)
        return Qn * s[None, :], R * s[:, None]

    QN, Rs = jax.lax.scan(step, Q0, G)
    return QN, Rs


def _blocks(B: np.ndarray, tol: float) -> tuple[list[tuple[int, int]], float]:
    """Greedy 1x1/2x2 partition of an (almost) block-diagonal orthogonal B and
    the size of what is left outside the blocks (the convergence measure)."""
    n = B.shape[0]
    blocks = []
    k = 0
    while k < n:
        if k + 1 < n and abs(B[k + 1, k]) > tol:
            blocks.append((k, 2))
            k += 2
        else:
            blocks.append((k, 1))
            k += 1
    mask = np.tril(np.ones_like(B, dtype=bool), -1)
    for k, s in blocks:
        if s == 2:
            mask[k + 1, k] = False
    return blocks, float(np.max(np.abs(B[mask]), initial=0.0))


@dataclass(frozen=True)
class PeriodicQRResult:
    multipliers: np.ndarray   # complex, sorted by decreasing modulus
    log_abs: np.ndarray       # log|mu| (finite even where mu under/overflows)
    sweeps: int
    off_block: float          # size of B outside its block diagonal (0 = exact)
    converged: bool


def multipliers_periodic(G: np.ndarray, *, tol: float = 1e-12, max_sweeps: int = 20,
                         block_tol: float = 1e-6) -> PeriodicQRResult:
    """Eigenvalues of G[N-1] ... G[0] by periodic QR iteration (see module doc).

    Each sweep costs N QR factorisations of n x n matrices.  Convergence of a
    subspace is linear with ratio |mu_{k+1}/mu_k|; with clustered moduli the
    iteration may stop at ``max_sweeps`` (``converged=False``): the block
    eigenvalues are then still returned, but only approximately (coupling
    outside the diagonal blocks is ignored; ``off_block`` measures it).
    """
    G = np.asarray(G, float)
    n = G.shape[-1]
    M = np.eye(n)
    for g in G:
        M = g @ M
    Q0 = _descending_basis(M)
    blocks: list = []
    B = np.eye(n)
    Gj = jnp.asarray(G)
    off = np.inf
    sweeps = 0
    for sweeps in range(1, max_sweeps + 1):
        QN, Rs = _sweep(Gj, jnp.asarray(Q0))
        QN = np.asarray(QN)
        B = Q0.T @ QN
        blocks, off = _blocks(B, block_tol)
        Q0 = QN
        if off < tol:
            break
    Rs = np.asarray(Rs)
    mus, logs = [], []
    for k, s in blocks:
        if s == 1:
            d = Rs[:, k, k]
            la = float(np.sum(np.log(np.abs(d)))) + np.log(abs(B[k, k]))
            sign = np.sign(B[k, k]) * np.prod(np.sign(d))
            mus.append(complex(sign * np.exp(la)))
            logs.append(la)
        else:
            P = np.eye(2)
            lsc = 0.0
            for R in Rs:
                P = R[k:k + 2, k:k + 2] @ P
                sc = np.max(np.abs(P))
                P /= sc
                lsc += np.log(sc)
            e = np.linalg.eigvals(B[k:k + 2, k:k + 2] @ P)
            for ee in e:
                la = lsc + np.log(abs(ee)) if ee != 0 else -np.inf
                mus.append(complex(np.exp(la) * ee / abs(ee)) if ee != 0 else 0j)
                logs.append(la)
    mus = np.array(mus)
    logs = np.array(logs)
    o = np.argsort(-logs, kind="stable")
    return PeriodicQRResult(mus[o], logs[o], sweeps, off, off < tol)


def _descending_basis(M: np.ndarray) -> np.ndarray:
    """Orthonormal basis whose leading k columns approximate the dominant
    k-dimensional invariant subspaces of M (QR of the eigenvectors sorted by
    decreasing modulus; a complex pair contributes Re v, Im v)."""
    ev, V = np.linalg.eig(M)
    order = np.argsort(-np.abs(ev), kind="stable")
    cols = []
    used = np.zeros(len(ev), bool)
    for i in order:
        if used[i]:
            continue
        used[i] = True
        v = V[:, i]
        if abs(ev[i].imag) > 0:
            cols += [v.real, v.imag]
            j = np.argmin(np.abs(ev - np.conj(ev[i])) + used * 1e300)
            used[j] = True
        else:
            cols.append(v.real)
    Q, _ = np.linalg.qr(np.array(cols[: len(ev)]).T)
    return Q


def trivial_index(mu: np.ndarray, count: int = 1) -> np.ndarray:
    """Indices of the ``count`` multipliers closest to +1."""
    return np.argsort(np.abs(np.asarray(mu) - 1.0))[:count]


def trivial_error(mu: np.ndarray) -> float:
    """Distance of the multiplier closest to +1 from +1."""
    return float(np.min(np.abs(np.asarray(mu) - 1.0)))


def nontrivial(mu: np.ndarray, count: int = 1) -> np.ndarray:
    """Multipliers with the ``count`` ones closest to +1 removed."""
    mu = np.asarray(mu)
    keep = np.ones(len(mu), bool)
    keep[trivial_index(mu, count)] = False
    return mu[keep]


# ---------------------------------------------------------------- Floquet methods (choices of CycleSettings)
class FloquetMethod:
    """How the multipliers of a converged cycle are computed from its :class:`~._linear.Linearisation`.
    ``multipliers(lin, memo)`` returns them sorted by decreasing modulus; ``memo`` is a dict that lives as long
    as the continuation (warm starts)."""

    def multipliers(self, lin, memo: dict) -> np.ndarray:  # pragma: no cover - interface
        raise NotImplementedError


@dataclass(frozen=True)
class PeriodicQR(FloquetMethod):
    """All n multipliers by the periodic QR iteration on the transfer matrices (relative accuracy for each, however
    many decades they span; see :func:`multipliers_periodic`)."""

    def multipliers(self, lin, memo: dict) -> np.ndarray:
        return multipliers_periodic(lin.transfer_matrices()).multipliers


@dataclass(frozen=True)
class TransferProduct(FloquetMethod):
    """All n multipliers as the eigenvalues of the explicit product of the transfer matrices (absolute accuracy
    eps * max|mu| only)."""

    def multipliers(self, lin, memo: dict) -> np.ndarray:
        mu = multipliers_product(lin.transfer_matrices())
        return mu[np.argsort(-np.abs(mu), kind="stable")]


@dataclass(frozen=True)
class _Leading(FloquetMethod):
    """The ``k`` (or more) multipliers of largest modulus, by a Krylov method on the monodromy operator (the
    matrix is never formed).  tol: relative tolerance of each multiplier's eigen-residual.  ``k`` is doubled until
    the smallest computed multiplier has modulus below ``inside``: events happen on the unit circle, and one at
    the edge of the computed set would be misread; once k would exceed n/2, all n multipliers are taken from the
    explicit product of the transfer matrices instead (as :class:`TransferProduct`)."""

    k: int = 12
    tol: float = 1e-11
    inside: float = 0.9

    def __post_init__(self) -> None:
        name = type(self).__name__
        store(self, "k", check_range(f"{name} k (number of multipliers)", self.k, 1, 10**6, integer=True))
        for field_, text in (("tol", "tol"), ("inside", "inside")):
            store(self, field_, check_range(f"{name} {text}", getattr(self, field_), 0.0, 1.0, lo_open=True,
                                            hi_open=True))


@dataclass(frozen=True)
class Arnoldi(_Leading):
    """The leading multipliers (see :class:`_Leading` for ``k``, ``tol``, ``inside``) by ARPACK's implicitly
    restarted Arnoldi, one sweep per product.  Along a branch the start vector is the sum of the previous point's
    Ritz vectors (the leading subspace moves little between points; saves about a quarter of the sweeps)."""
    def multipliers(self, lin, memo: dict) -> np.ndarray:
        # Every bifurcation happens on the unit circle: the computed set must reach well inside it.  With k
        # multipliers at or near the circle (a torus branch with several pairs outside) the critical pair can be
        # the k-th, or split by the cut from its conjugate (then taken for a real multiplier at +1: a false BPC);
        # so k grows until the smallest computed modulus is below ``inside``.
        n = lin.orbit.n
        k = int(min(self.k, n - 2))
        while True:
            if 2 * k > n:  # most of the spectrum: cheaper all at once, from the explicit product (n products)
                mu = multipliers_product(lin.transfer_matrices())
                return mu[np.argsort(-np.abs(mu), kind="stable")]
            mu = self._leading(lin, memo, k)
            if abs(mu[-1]) < self.inside:
                return mu
            k = 2 * k

    def _leading(self, lin, memo: dict, k: int) -> np.ndarray:
        import scipy.sparse.linalg as spla

        from ._newton import LinearSolveError

        n = lin.orbit.n
        M = spla.LinearOperator((n, n), matvec=lin.monodromy_matvec, dtype=float)
        ones = np.ones(n) / np.sqrt(n)
        v0 = memo.get("arnoldi_start")
        v0 = ones if v0 is None or v0.shape != (n,) else v0
        err = None
        for ncv in (max(2 * k + 1, 30), 4 * k + 20):  # a larger Krylov space if ARPACK does not converge
            try:
                mu, V = spla.eigs(M, k=k, which="LM", v0=v0, tol=self.tol, ncv=min(n, ncv), maxiter=50 * n)
            except spla.ArpackNoConvergence as e:
                err, v0 = e, ones
                continue
            v = np.real(V).sum(axis=1) + np.imag(V).sum(axis=1)
            nv = float(np.linalg.norm(v))
            memo["arnoldi_start"] = v / nv if np.isfinite(nv) and nv > 0 else None
            return mu[np.argsort(-np.abs(mu), kind="stable")]
        memo["arnoldi_start"] = None
        raise LinearSolveError(f"Arnoldi (ARPACK) did not converge for the {k} leading Floquet multipliers: {err}")


@dataclass(frozen=True)
class BlockKrylov(_Leading):
    r"""The leading multipliers (see :class:`_Leading` for ``k``, ``tol``, ``inside``) by Rayleigh-Ritz on a block
    Krylov space of the monodromy operator, grown without restarts.

    The space is :math:`\mathrm{span}\{V_0, MV_0, M^2V_0, \dots\}` with a start block :math:`V_0` of ``block``
    columns or more: the previous point's leading Ritz vectors (the dominant subspace moves little along a
    branch) and at least four fixed pseudo-random columns (so that no direction is missed; see
    :func:`krylov_leading` for the checks that keep a warm start from missing a newly leading multiplier).  Each
    product is one block sweep of the linearisation (``monodromy_matmat``), whose factorisations are read once per
    block instead of once per vector.
    Because every product :math:`MQ` is kept, each Ritz pair's residual :math:`\|MQy - \theta Qy\|` is computed
    exactly, not estimated; the space grows until it is at most ``tol`` :math:`|\theta|` for every returned
    multiplier of modulus at least ``inside``, and ``tol_inside`` :math:`|\theta|` for those further in.  Those
    only show that nothing else is near the unit circle, and enter the test functions as factors far from zero
    (an error there scales a test function, it does not move its zero); the GFB's film modes crowd there in a
    continuum, where a tight tolerance would need a space about twice as large.  Below modulus 1e-3 the residual
    is measured against 1e-3 instead of :math:`|\theta|`: such a multiplier is zero to every test function, and
    relative digits of a nearly annihilated mode cannot be had.  If ``max_dim`` columns do not suffice, the
    multipliers come from :class:`Arnoldi` instead.
    """

    block: int = 16
    max_dim: int = 640
    tol_inside: float = 1e-6

    def __post_init__(self) -> None:
        super().__post_init__()
        store(self, "block", check_range("BlockKrylov block", self.block, 1, 10**4, integer=True))
        store(self, "tol_inside", check_range("BlockKrylov tol_inside", self.tol_inside, self.tol, 1.0,
                                              hi_open=True))
        store(self, "max_dim", check_range("BlockKrylov max_dim", self.max_dim, 2, 10**6, integer=True))

    def multipliers(self, lin, memo: dict) -> np.ndarray:
        n = lin.orbit.n
        if 2 * min(self.k, n - 2) > n:
            mu = multipliers_product(lin.transfer_matrices())
            return mu[np.argsort(-np.abs(mu), kind="stable")]
        out = krylov_leading(lin.monodromy_matmat, n, k=min(self.k, n - 2), inside=self.inside, tol=self.tol,
                             tol_inside=self.tol_inside, block=self.block, max_dim=min(self.max_dim, n),
                             start=memo.get("krylov_start"), vectors=True)
        if out is None:  # not converged within max_dim: the restarted method (ARPACK) takes over
            memo["krylov_start"] = None
            return Arnoldi(self.k, self.tol, self.inside).multipliers(lin, memo)
        mu, basis, X = out
        if 2 * len(mu) > n:  # most of the spectrum is wanted: all of it, from the explicit product
            mu = multipliers_product(lin.transfer_matrices())
            return mu[np.argsort(-np.abs(mu), kind="stable")]
        # the leading Ritz pairs of this point, for the estimate of their error (_resolution.mode_error)
        memo["krylov_start"], memo["modes"] = basis, (mu, X)
        return mu


#: Relative residual the two Ritz values after the cut must reach: only that they are eigenvalues, so that the cut
#: falls between true ones, not their digits.
_GUARD_TOL = 1e-3

#: Modulus below which a Ritz value's residual is measured against this floor instead of its own modulus.  Every
#: bifurcation happens on the unit circle, so a multiplier of modulus 1e-3 or 1e-12 is "zero" to every test function
#: (a factor mu + 1, mu - 1 or mu_i mu_j - 1 within 1e-3 of +-1); asking such multipliers for relative digits asks
#: for the impossible where the spectrum is mostly damped (Radau points damp the stiff film modes to 1e-10 and
#: below: the space then grew to its limit at every point, 5x the cost of the whole Floquet step).
_MODULUS_FLOOR = 1e-3


def krylov_leading(matmat, n: int, *, k: int, inside: float, tol: float, tol_inside: float, block: int,
                   max_dim: int,
                   start: np.ndarray | None = None, vectors: bool = False) -> tuple[np.ndarray, ...] | None:
    """Leading eigenvalues of the operator ``matmat`` ((n, b) -> (n, b)) by block Krylov Rayleigh-Ritz (see
    :class:`BlockKrylov`).  Returns (eigenvalues sorted by decreasing modulus, an orthonormal real basis (n, c) of
    their Ritz vectors for the next start), with ``vectors`` also the Ritz vectors themselves (n, count), or None
    when ``max_dim`` columns did not converge them.

    The count returned is k, doubled while the smallest has modulus >= ``inside``, and made closed under
    conjugation (a pair is never cut from its conjugate).

    A start basis converges at once to what it already holds, and an eigenvalue outside it (a multiplier that has
    just grown past the others) shows first as a poor Ritz value of the random columns, which may sit below the
    cut where nothing is checked.  So the start keeps at least four random columns, the space is grown by at least
    three block products before anything is returned, and the two Ritz values after the cut must have converged
    as well (to 1e-3): the returned set is then the leading one, not just a converged one."""
    b = max(1, min(block, n))
    # A new column whose part outside the space is below ``drop`` (relative) is left out.  That part is what the
    # space still lacks, and a pair held to ``tol`` may lack exactly such parts: so ``drop`` lies below ``tol``.
    # At 1e-10 (above tol = 1e-11) a warm start from the last point's nearly exact Floquet vectors lost them: on the
    # GFB reference grid at the NS point the leading pair's residual stalled at 6e-11 and the space grew to all 433
    # columns, where a cold start needs 176 (now 120; tests/cont/test_cont_sparse.py has a case).  The price: a
    # start exact to 1e-12 keeps columns it does not need and costs about a cold start, where dropping them made
    # the blocks narrow (4 new columns each) and the start cheaper (~100 columns against 176 there).  On the whole
    # reference branch the multipliers take 5,886 columns against 6,213 (benchmarks/README.md, cycle_branch.py).
    drop = min(1e-10, max(1e-1 * tol, 100 * np.finfo(float).eps))
    warm = start is not None and start.shape[0] == n
    # a whole block of fixed pseudo-random columns, or, after a warm start, enough to top it up (at least 4)
    fill = np.random.default_rng(0).standard_normal((n, max(b - start.shape[1], 4) if warm else b))
    V0 = np.concatenate([start, fill], axis=1) if warm else fill
    Q = _orthonormal(V0, None, drop=True)
    min_dim = min(n, Q.shape[1] + 3 * b)
    guard = 2
    Qs, Ws = [Q], []
    while True:
        Ws.append(np.asarray(matmat(Qs[-1]), float))
        Qa, Wa = np.concatenate(Qs, axis=1), np.concatenate(Ws, axis=1)
        theta, Y = np.linalg.eig(Qa.T @ Wa)
        order = np.argsort(-np.abs(theta), kind="stable")
        theta, Y = theta[order], Y[:, order]
        count = _wanted(theta, k, inside)
        dim = Qa.shape[1]
        if dim >= n and count <= dim:  # the whole space: the Ritz values are the eigenvalues
            X = Qa @ Y[:, :count]
            return (theta[:count], _ritz_basis(X)) + ((X,) if vectors else ())
        checked = count + guard
        if dim >= min_dim and checked <= dim:
            Yc = Y[:, :checked]
            res = np.linalg.norm(Wa @ Yc - (Qa @ Yc) * theta[:checked], axis=0)
            mod = np.abs(theta[:checked])
            scale = np.maximum(mod, _MODULUS_FLOOR)
            need = np.where(mod >= inside, tol, tol_inside) * scale
            need[count:] = _GUARD_TOL * scale[count:]
            if np.all(res <= need):
                X = Qa @ Yc[:, :count]
                return (theta[:count], _ritz_basis(X)) + ((X,) if vectors else ())
        if dim >= max_dim:
            return None
        nxt = _orthonormal(Ws[-1][:, :max_dim - dim], Qa, drop=True, inside=drop)
        if nxt.shape[1] == 0:  # the space is invariant: fill with fresh directions
            nxt = _orthonormal(np.random.default_rng(dim).standard_normal((n, min(b, max_dim - dim))), Qa,
                               drop=True)
            if nxt.shape[1] == 0:
                return None
        Qs.append(nxt)


def _ritz_basis(X: np.ndarray) -> np.ndarray:
    """An orthonormal real basis of the span of complex Ritz vectors X (n, c)."""
    return _orthonormal(np.concatenate([X.real, X.imag], axis=1), None, drop=True)


def _wanted(theta: np.ndarray, k: int, inside: float) -> int:
    """How many of the Ritz values theta (decreasing modulus) to return: k, doubled while the last is at or outside
    ``inside``, then one more while the set is not closed under conjugation (a pair cut at the end)."""
    count = min(k, len(theta))
    while count < len(theta) and abs(theta[count - 1]) >= inside:
        count = min(2 * count, len(theta))
    scale = max(float(np.max(np.abs(theta[:count]), initial=0.0)), 1e-300)
    while count < len(theta):
        im = theta[:count].imag
        if np.sum(im > 1e-12 * scale) == np.sum(im < -1e-12 * scale):
            break
        count += 1
    return count if abs(theta[count - 1]) < inside else len(theta) + 1  # all at or outside: grow the space


def _orthonormal(V: np.ndarray, against: np.ndarray | None, drop: bool = False,
                 inside: float = 1e-10) -> np.ndarray:
    """Orthonormal columns spanning V minus its part in span(against) (orthonormal); two passes of classical
    Gram-Schmidt then a QR; with ``drop`` the columns that were (numerically) inside are left out: those whose
    part outside (after pivoting) is at most ``inside`` times the longest column of V."""
    import scipy.linalg as sla

    V = np.array(V, float)
    scale = float(np.max(np.linalg.norm(V, axis=0), initial=0.0))
    if against is not None:
        for _ in range(2):
            V -= against @ (against.T @ V)
    if not drop:
        return np.linalg.qr(V)[0]
    Q, R, _ = sla.qr(V, mode="economic", pivoting=True)
    rank = int(np.sum(np.abs(np.diag(R)) > inside * max(scale, 1e-300)))
    Q = Q[:, :rank]
    if against is not None and rank:
        # a column that lost most of its length to the projection keeps rounding errors of the original size:
        # orthogonalise the normalised columns once more
        Q -= against @ (against.T @ Q)
        Q = np.linalg.qr(Q)[0]
    return Q
