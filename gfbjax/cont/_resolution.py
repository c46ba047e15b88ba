r"""Does the mesh resolve the modes of the linearisation?  Where it does not, Floquet multipliers are wrong while
the orbit, its mesh estimate and the trivial multiplier are all accurate.

Collocation integrates the variational equation over each mesh interval with the scheme's stability function R
(:meth:`~._collocation.Scheme.stability`): a mode y' = lam y is multiplied by R(h lam) per interval of length h
(in the problem's time) instead of exp(h lam).  The orbit does not contain these modes (they are not excited), so
its mesh estimate cannot see how well they are resolved.  Two ways it goes wrong:

* **fast modes** (|h lam| >> 1, strongly damped): with Gauss points |R| -> 1, so a mode that decays by
  exp(lam T) ~ 0 over the period keeps a multiplier near the unit circle.  On the GFB reference grid at N = 16 the
  film's modes (lam ~ -600) give a band of spurious multipliers at |mu| 0.33 at the Neimark-Sacker speed and 0.91
  at Omega_bar 0.05.  Radau points (L-stable) put them near 0.
* **modes oscillating within an interval** (|h Im lam| ~ 1 or more, weakly damped): at low speed the period
  T = 2 pi / Omega_bar is long, and the rotor's own oscillation completes about a cycle per interval.  On the
  16x2 grid at Omega_bar 0.1 and N = 16 the leading pair's modulus comes out 0.283 with Gauss points and 0.044
  with Radau points; it is 0.247 (N = 64 and 128 with both, and exp(lam T) of the equilibrium's rotor mode).

Both are estimated by :func:`resolution` from the frozen-coefficient model: the eigenvalues lam of f_x at mesh
nodes spread over the period (every node where that costs at most :data:`FROZEN_BUDGET` flops, n <= 100 at
N = 20; else as many as fit, at least :data:`NODES`; the largest estimate of them is kept, so that it does not
hang on one point of the orbit; with fewer nodes than intervals it depends on the time origin where f_x changes
much between them, see "Limits" below), each mode's multiplier prod_i R(h_i lam) on the mesh against exp(lam T)
exactly:

* ``stiff_modulus``: the largest modulus the mesh gives a fast mode (exact multiplier below :data:`FAST`; its
  exact value is about 0): the band of spurious multipliers;
* ``multiplier_error``: the largest error |prod R - exp(lam T)| / max(1, |exp(lam T)|) (modulus and phase) of a
  visible mode (exact multiplier at least :data:`FAST`) or of a fast mode whose spurious multiplier reaches
  :data:`DECIDING` of the leading non-trivial modulus (capped at 1), i.e. pretends to decide stability, events or
  the leading multiplier.  A spurious band further inside changes none of these and is not counted.

The model is exact for a constant Jacobian (tests/cont/test_cont_resolution.py) and a guide otherwise: it says
where the multipliers need a finer mesh (or Radau points for the fast modes), not by how much they are off on a
cycle far from a constant-coefficient one.  Its cost is a dense eigenvalue problem per node and recorded point
(n = 433: about 3 s over the reference branch); above :data:`MAX_DENSE` states it is skipped (NaN: not
estimated).

**Propagated mode defects** (:func:`mode_error`).  The frozen model cannot see how f_x varies along the orbit,
and a kink of f is a jump of f_x: the bearing's max(p - 1, 0), a contact spring.  There the variational equation
is one order less smooth than the orbit.  f is continuous, so an interval that holds the kink puts an error of
order h^2 k into the orbit (k: the jump of f_x), but f_x jumps by k, so it puts an error of order h k into each
interval's transfer matrix, whatever m.  On a stiff contact that the cycle grazes (k = 1e3,
tests/cont/test_cont_mesh.py) the orbit passed its mesh test at N = 1536-4096 (5e-5 from the exact cycle) while
its multipliers were off by 0.09-0.55, a real pair in place of a complex one.  The estimate treats each deciding
Floquet mode as the orbit's error estimate (:mod:`._mesh`) treats the orbit:

* the modes: the deciding multipliers and the trivial one, with their eigenvectors (the block Krylov method's
  Ritz pairs; with the dense solver, the eigenvectors of the explicit monodromy), spanned by a real orthonormal
  basis Q; one block sweep of the linearisation gives their collocation polynomials over the period and
  H = Q^T M Q;
* the running defects of those polynomials against the variational equation y' = T f_x(x(t)) y, by the finer
  quadrature of :func:`~._mesh.running_defects`, with f_x at the orbit's own polynomial;
* each interval's defect, spread evenly over it and carried from zero through one period by a second block
  sweep: y(T) - Y(T) = E, the difference from the exact solutions Y of the variational equation from the same
  start, so that the exact monodromy acts on the span as M Q - E;
* the error of each deciding multiplier: its distance from the nearest eigenvalue of H - Q^T E, relative to
  max(1, |mu|).

The correction is first order in the defects, so it holds where each interval's transfer matrix is nearly right.
Measured (estimate / true error): the grazing contact, Gauss and Radau, m = 2 and 4, N = 256-4096: 0.5-2.2 in 16 of
17 cases where the orbit's mesh error is below 1e-2, and 0.16 in one (Radau m = 4, N = 2048: 0.014 for 0.086); at
N = 64 (mesh errors 1e-2 to 4e-2, flagged for those) 0.001-0.16. Van der Pol, mu = 0.5 (multiplier 0.039), N = 6-12,
Gauss and Radau: 0.4-7.4 (true errors 2e-8 to 2e-4; on errors below 1e-7, at N = 16 and 32, 0.13-6.4).  The GFB
reference grid (48x8), N = 16 / 24 / 32 against N = 128, at the NS speed: 1.2 / 4.7 / 2.2 (true 4.1e-4 / 3.2e-5 /
3.6e-5), at Omega_bar 0.55: 1.3 / 1.9 / 1.6 (true 3.8e-4 / 1.3e-4 / 2.2e-4; the kinks make the error fall
erratically with N).  It does not see a mode oscillating within an interval (h |lam| ~ 1) on a constant Jacobian:
there the defect's integral over each interval vanishes by the collocation conditions (Gauss and Radau quadrature
are exact for it), and the error lies in how the interval's own step propagates, which the frozen model computes
exactly (and the halved intervals below, Jacobian constant or not).  Each estimate covers cases the others miss, so
a recorded point carries the largest (:func:`multiplier_estimates`).  Cost per recorded point: two block sweeps of a
few columns and the linearised field at N m (m + 2) points per column; on the reference branch 0.05-0.26 s, 5.4 s
over the branch (benchmarks/README.md, cycle_branch.py and multiplier_accuracy.py).

**Halved intervals** (:func:`halved_error`).  Neither estimate above sees a mode that is stiff on only part of
the period (it oscillates within an interval there, on a smooth field): the frozen model sees it only where one
of its nodes falls on that part, and the mode defects not at all.  In the review case of session 11
(tests/cont/test_cont_resolution.py) Radau points, N = 40, computed a pair of modulus 0.83 (stable) for the exact
1.02 (unstable), both estimates 1.2e-4 (the frozen model then at two nodes), unflagged; a quarter period later in
time the frozen model flagged the same cycle.  The third estimate asks the discretisation itself: the orbit's
polynomial is sampled on the mesh with every interval halved (not corrected there: it is already accurate, which
the mesh estimate checks) and linearised there by the branch's solver.  Where all multipliers are at hand (the
dense solver, or at most :data:`EXPLICIT_N` states) both monodromies are formed and their whole spectra compared:
each multiplier deciding on either mesh (at least :data:`DECIDING` of the larger leading modulus, and
:data:`FAST`), its distance from the other spectrum, relative to max(1, |mu|).  Otherwise one block sweep on the
halved mesh carries the basis Q above (the modes deciding at N) through the period, and each deciding multiplier's
distance from the nearest eigenvalue of Q^T M_2N Q is taken; this projection is first order in the change, an
estimate, not a bound, where the modes themselves move, and it cannot see a mode that the N mesh damps below the
deciding floor.  The change on halving is (1 - 2^-p) of the error where the error falls as h^p (Gauss and Radau
points, p = 2m and 2m - 1), and a fraction of it where a kink makes it fall erratically (there the mode defects
stand in).  Measured on the review case (estimate / true error): Radau N = 40 and 80, Gauss N = 20 and 40:
0.70-0.99 (true errors 2.9e-3 to 0.25, mostly in the angle: the mode turns about 40 rad on its stiff stretch).  On
the GFB reference grid (projection) it agrees with the mode defects (0.38-4.6x the true error against N = 128,
benchmarks/multiplier_accuracy.py).  Cost per recorded point: one linearisation on 2N intervals (a compilation for
2N once per branch) and one block sweep of a few columns, or the two explicit monodromies; on the reference branch
0.25 s, 16 s over the branch (benchmarks/README.md, cycle_branch.py).

Limits. The review of session 12 found two more ways past the estimates, both now caught where the frozen model
freezes f_x at every node (tests/cont/test_cont_resolution.py): a mode that N and 2N both damp away (Radau points, a
stiffness 2500x on a stretch of the period: exact multipliers 2.76 and 0.35, computed below 3e-4 on N = 20, 40 and
80), and Gauss points on a stiff stretch that begins and ends on mesh nodes (R(-inf) = 1 on every interval of it, on
both meshes). Where the frozen model has fewer nodes than intervals (large n: two nodes on the GFB reference grid)
these cases are caught only where a node falls on the stretch, and with the sparse solver above :data:`EXPLICIT_N`
states the halved estimate does not see a mode that the N mesh damps below the deciding floor. A kink that the orbit
crosses between two quadrature points (a contact 1e-6 deep, open for 4e-4 of the period, N = 64) is missed by the
collocation and the estimates alike, depending on the time origin. Where :func:`mode_error` or :func:`halved_error`
is NaN (the modes do not match the spectrum) the others stand, unflagged for that reason.
"""
from __future__ import annotations

import math
from functools import partial
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from . import _collocation as col
from ._floquet import _ritz_basis, monodromy_product, nontrivial
from ._mesh import halved_mesh, remesh, running_defects_linear
from ._newton import LinearSolveError

__all__ = ["resolution", "mode_error", "halved_error", "multiplier_estimates", "DECIDING", "FAST", "NODES",
           "FROZEN_BUDGET", "EXPLICIT_N", "MAX_DENSE"]

#: a mode whose exact multiplier is below this modulus is a fast mode (:func:`resolution`'s ``stiff_modulus``)
FAST = 1e-3
#: the fewest mesh points (evenly spread over the period) at which the Jacobian is frozen
NODES = 2
#: the dense eigenvalue work (about 10 n^3 flops per node) the frozen model may spend per recorded point: it
#: freezes the Jacobian at every mesh node where that fits (n <= 100 at N = 20), else at as many, evenly spread
FROZEN_BUDGET = 2.5e8
#: the largest state dimension for which :func:`halved_error` compares the whole spectra of both meshes when the
#: linear solver is sparse (a block sweep of n columns per mesh); the dense solver always does
EXPLICIT_N = 64
#: a mode decides (stability, events, the leading multiplier) when its exact or discrete multiplier reaches this
#: fraction of the leading non-trivial modulus (capped at 1): a spurious band further in changes none of them
DECIDING = 0.9
#: the largest state dimension for which the dense eigenvalue problems are solved
MAX_DENSE = 1500
#: the most stability-function systems (intervals x modes x frozen nodes) :func:`resolution` solves in one batch
STABILITY_BATCH = 100_000


@partial(jax.jit, static_argnums=(0,))
def _jacobians(f: Callable, xs: jax.Array, lam: jax.Array, args: Any) -> jax.Array:
    return jax.vmap(jax.jacfwd(lambda y: f(y, lam, args)))(xs)


def resolution(f: Callable, orbit: col.Orbit, args: Any, scheme: col.Scheme,
               leading: float = 1.0) -> tuple[float, float]:
    """(stiff_modulus, multiplier_error) of a converged orbit on its mesh, both dimensionless (module docstring);
    ``leading``: the largest non-trivial multiplier's modulus at the point.  (NaN, NaN) above
    :data:`MAX_DENSE` states."""
    if orbit.n > MAX_DENSE:
        return math.nan, math.nan
    N = orbit.N
    k = min(N, max(NODES, int(FROZEN_BUDGET // (10.0 * orbit.n ** 3))))
    at = np.unique((np.arange(k) * N) // k)
    J = np.asarray(_jacobians(f, jnp.asarray(np.asarray(orbit.xm)[at]), orbit.lam, args))
    h = float(orbit.T) * np.diff(np.asarray(orbit.mesh, float))
    T = float(np.sum(h))
    # the frozen nodes in batches (one eigenvalue call and one stability call per batch), not one at a time: at
    # small n the Python loop over the nodes was most of the estimate's time; batches of at most STABILITY_BATCH
    # stability systems (m x m each) bound the memory (all nodes at once took 2 GB at n = 30, N = 300, m = 5)
    stiff, error = 0.0, 0.0
    per = max(1, STABILITY_BATCH // (len(h) * orbit.n))
    for first in range(0, len(J), per):
        lam = np.linalg.eigvals(J[first:first + per])
        exact = np.exp(np.clip(lam.real * T, -700.0, 700.0) + 1j * lam.imag * T)
        discrete = np.prod(scheme.stability(h[:, None, None] * lam[None]), axis=0)
        fast = np.abs(exact) < FAST
        stiff = max(stiff, float(np.max(np.abs(discrete[fast]), initial=0.0)))
        deciding = np.maximum(np.abs(exact), np.abs(discrete)) >= DECIDING * min(1.0, leading)
        err = np.abs(discrete - exact) / np.maximum(1.0, np.abs(exact))
        error = max(error, float(np.max(err[deciding | ~fast], initial=0.0)))
    return stiff, error


def _deciding_modes(orbit: col.Orbit, lin: Any, spectrum: np.ndarray, modes: tuple[np.ndarray, np.ndarray] | None,
                    n_trivial: int) -> tuple[np.ndarray, np.ndarray] | float:
    """(want, Q): the deciding multipliers (k,) and a real orthonormal basis Q (n, c) of their Floquet modes with
    the trivial one; or 0.0 where no multiplier is deciding, NaN where ``modes`` lacks one of them (or, without
    ``modes``, above :data:`MAX_DENSE` states)."""
    mu = np.asarray(spectrum)
    nt = nontrivial(mu, n_trivial)
    if nt.size == 0:
        return 0.0
    # Fast modes (exact multiplier below FAST) are the frozen model's: an error far below 1 in a multiplier near 0
    # decides nothing, and a mode that decays by many decades over the period has no small relative defect.
    floor = max(DECIDING * min(1.0, float(np.max(np.abs(nt)))), FAST)
    if not np.any(np.abs(nt) >= floor):
        return 0.0
    if modes is None:
        if orbit.n > MAX_DENSE:
            return math.nan  # no Ritz pairs, and the explicit monodromy would cost too much: not estimated
        modes = np.linalg.eig(monodromy_product(lin.transfer_matrices()))
    ev, V = (np.asarray(a) for a in modes)
    want = nt[np.abs(nt) >= floor]
    if np.any(np.min(np.abs(want[:, None] - ev[None, :]), axis=1) > 1e-6 * np.maximum(1.0, np.abs(want))):
        return math.nan  # the modes are not those of this spectrum: no estimate
    # the deciding modes with the trivial one (floor <= 0.9)
    return want, _ritz_basis(V[:, np.abs(ev) >= floor])


def _distance(want: np.ndarray, H: np.ndarray) -> float:
    """The largest distance of a deciding multiplier from the nearest eigenvalue of H, relative to max(1, |mu|)."""
    ev = np.linalg.eigvals(H)
    return float(np.max(np.min(np.abs(want[:, None] - ev[None, :]), axis=1) / np.maximum(1.0, np.abs(want))))


def mode_error(f: Callable, args: Any, orbit: col.Orbit, scheme: col.Scheme, lin: Any, spectrum: np.ndarray,
               modes: tuple[np.ndarray, np.ndarray] | None = None, n_trivial: int = 1) -> float:
    """The largest estimated error of the deciding multipliers (the non-trivial ones of modulus at least
    :data:`DECIDING` times min(1, the leading non-trivial modulus), and at least :data:`FAST`), relative to
    max(1, |mu|), from the running defects of their Floquet modes (module docstring, "Propagated mode defects").
    Dimensionless; 0 where no multiplier is deciding, NaN where the defects are not finite or ``modes`` lacks a
    deciding multiplier.

    lin: the orbit's :class:`~._linear.Linearisation`; spectrum: its multipliers (decreasing modulus); modes:
    (multipliers (k,), eigenvectors (n, k)) of the collocation monodromy that hold the deciding ones and the
    trivial one (the block Krylov method's Ritz pairs); default: from the explicit product of the transfer
    matrices (NaN above :data:`MAX_DENSE` states)."""
    d = _deciding_modes(orbit, lin, spectrum, modes, n_trivial)
    if isinstance(d, float):
        return d
    want, Q = d
    # the modes' collocation polynomials over the period from one block sweep (xs[-1] = M Q)
    N, m, n, c = orbit.N, scheme.m, orbit.n, Q.shape[1]
    xs, ws = lin.sweep(Q, np.zeros(2))
    H = Q.T @ xs[-1]
    Y = np.moveaxis(np.concatenate([xs[:-1, None], ws, xs[1:, None]], axis=1), -1, 0)  # (c, N, m+1, n)
    # in blocks of 4 columns (the last padded with zeros): one compilation serves every size of the subspace (the
    # spurious band at low speed makes it 10-20 columns on the reference branch)
    Y = np.concatenate([Y, np.zeros((-c % 4,) + Y.shape[1:])])
    D = np.concatenate([running_defects_linear(f, args, orbit, Y[i:i + 4], scheme)
                        for i in range(0, len(Y), 4)])[:c]
    if not np.all(np.isfinite(D)):
        return math.nan
    # Each interval's defect, spread evenly over it and carried from zero through the period, gives y(T) - Y(T)
    # for the exact solutions Y of the variational equation from the same start: the exact M Q is M Q - E.
    rc = np.repeat(D[:, :, None, -1], m, axis=2).reshape(c, N, m * n)
    E = lin.sweep(np.zeros((n, c)), np.zeros(2), np.moveaxis(rc, 0, -1))[0][-1]
    return _distance(want, H - Q.T @ E)


def _spectra_change(mu: np.ndarray, mu2: np.ndarray, n_trivial: int) -> float:
    """The largest distance, relative to max(1, |mu|), of a deciding multiplier of either spectrum (non-trivial, of
    modulus at least :data:`DECIDING` times min(1, the leading non-trivial modulus of both), and at least
    :data:`FAST`) from the other spectrum's non-trivial multipliers; 0 where none is deciding."""
    a, b = nontrivial(mu, n_trivial), nontrivial(mu2, n_trivial)
    if a.size == 0 or b.size == 0:
        return 0.0
    floor = max(DECIDING * min(1.0, float(max(np.max(np.abs(a)), np.max(np.abs(b))))), FAST)
    out = 0.0
    for x, y in ((a, b), (b, a)):
        x = x[np.abs(x) >= floor]
        if x.size:
            out = max(out, float(np.max(np.min(np.abs(x[:, None] - y[None, :]), axis=1) / np.maximum(1.0, np.abs(x)))))
    return out


def halved_error(orbit: col.Orbit, scheme: col.Scheme, lin: Any, spectrum: np.ndarray,
                 linearise: Callable[[col.Orbit], Any], modes: tuple[np.ndarray, np.ndarray] | None = None,
                 n_trivial: int = 1) -> float:
    """The change of the deciding multipliers when every mesh interval is halved, relative to max(1, |mu|):
    module docstring, "Halved intervals".  With all multipliers at hand (the dense solver: ``modes`` None, or at
    most :data:`EXPLICIT_N` states) both whole spectra are compared (both from the transfer matrices, so that they
    are alike), and a multiplier deciding on either mesh counts; otherwise the deciding modes at N (as in :func:`mode_error`) are carried through the halved mesh.
    Dimensionless; 0 where no multiplier is deciding, NaN where ``modes`` lacks one or the halved linearisation is
    singular or not finite.

    linearise: orbit -> its :class:`~._linear.Linearisation` on that orbit's mesh (the branch's own solver, for
    the orbit's polynomial sampled on the halved mesh); the other arguments as for :func:`mode_error`."""
    explicit = (modes is None and orbit.n <= MAX_DENSE) or orbit.n <= EXPLICIT_N
    d = None if explicit else _deciding_modes(orbit, lin, spectrum, modes, n_trivial)
    if isinstance(d, float):
        return d
    try:
        fine = linearise(remesh(orbit, scheme, halved_mesh(orbit.mesh)))
        if explicit:
            G, G2 = lin.transfer_matrices(), fine.transfer_matrices()
            if not (np.all(np.isfinite(G)) and np.all(np.isfinite(G2))):
                return math.nan
            return _spectra_change(np.linalg.eigvals(monodromy_product(G)),
                                   np.linalg.eigvals(monodromy_product(G2)), n_trivial)
        want, Q = d
        MQ = fine.sweep(Q, np.zeros(2))[0][-1]
    except LinearSolveError:  # a singular interval block on the halved mesh: not estimated, the others stand
        return math.nan
    if not np.all(np.isfinite(MQ)):
        return math.nan
    return _distance(want, Q.T @ MQ)


def multiplier_estimates(f: Callable, args: Any, orbit: col.Orbit, scheme: col.Scheme, lin: Any,
                         spectrum: np.ndarray, modes: tuple[np.ndarray, np.ndarray] | None = None,
                         n_trivial: int = 1, linearise: Callable[[col.Orbit], Any] | None = None
                         ) -> tuple[float, float]:
    """(stiff_modulus, multiplier_error) that a recorded cycle carries: the frozen-coefficient model's
    (:func:`resolution`) and, for the error, the largest of its estimate, the mode defects' (:func:`mode_error`)
    and, given ``linearise`` (orbit -> Linearisation, the branch's solver), the change on halved intervals
    (:func:`halved_error`): each sees cases the others miss (module docstring, with the limits).  NaN only where
    none is estimated."""
    nt = np.abs(nontrivial(np.asarray(spectrum), n_trivial))
    stiff, frozen = resolution(f, orbit, args, scheme, float(np.max(nt, initial=0.0)))
    error = np.fmax(frozen, mode_error(f, args, orbit, scheme, lin, spectrum, modes, n_trivial))
    if linearise is not None:
        error = np.fmax(error, halved_error(orbit, scheme, lin, spectrum, linearise, modes, n_trivial))
    return stiff, float(error)
