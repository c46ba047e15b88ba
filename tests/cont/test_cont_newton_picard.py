"""The Newton-Picard preconditioner of the sparse solver's reduced system (``_sweeps.NewtonPicard``).

A preconditioner may change how many GMRES iterations a solve takes, never its answer: every solve is compared
with the dense condensation's direct solve of the same Newton system, with the leading Floquet subspace of a nearby
orbit, of the orbit itself, and with a subspace that has nothing to do with the operator.  The iteration counts are
counted, not timed: the ring's reduced operator has many eigenvalues 1 - mu far from 1 (the slow diffusion modes,
mu = exp(-dq T) up to 1), and those are what a subspace of their eigenvectors removes.
"""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

from gfbjax import cont
from gfbjax.cont import _collocation as col
from gfbjax.cont import BlockKrylov, DenseCondensation, SparseSweep
from gfbjax.cont import _sweeps
from gfbjax.cont._sweeps import NewtonPicard

from cont_systems import ring, ring_pattern

LAM, W, D = 0.5, 2 * np.pi, 1.0


def _ring_problem(k):
    return cont.CycleProblem(f=ring, n=2 * k, args=jnp.array([W, D]), jac_sparsity=ring_pattern(k))


def _guess(k, sch, N, lam=LAM, amp=(1.05, 0.95), twist=0.3):
    r = np.sqrt(lam)
    phase = twist * np.sin(2 * np.pi * np.arange(k) / k)

    def x_of_t(t):
        th = 2 * np.pi * t[:, None] + phase[None, :]
        return np.stack([amp[0] * r * np.cos(th), amp[1] * r * np.sin(th)], axis=2).reshape(len(t), -1)

    return col.orbit_from_function(x_of_t, 1.02 * 2 * np.pi / W, lam, sch, col.uniform_mesh(N))


class _Count:
    """Counts the reduced operator's products (GMRES matvecs) of every solve."""

    def __init__(self, monkeypatch):
        self.products = 0
        real = _sweeps.IntervalSweeps._gmres

        def counting(lin, matvec, b, rtol=None):
            def mv(v):
                self.products += 1
                return matvec(v)
            return real(lin, mv, b, rtol)

        monkeypatch.setattr(_sweeps.IntervalSweeps, "_gmres", counting)


@pytest.fixture(scope="module")
def ring40():
    """The ring of 40 oscillators (n = 80), its cycle at lam = LAM, and the leading Floquet subspace there."""
    k = 40
    prob, sch = _ring_problem(k), cont.Scheme(4)
    newton = cont.NewtonSettings(tol=1e-11, atol_step=1e-11, rtol_step=1e-11, max_iter=12)
    sol, lin = SparseSweep().bind(prob, sch).correct(_guess(k, sch, 16), col.natural_constraint(
        _guess(k, sch, 16), LAM), newton)
    assert sol.converged
    memo = {}
    mu = BlockKrylov(k=16).multipliers(lin, memo)
    assert np.sum(np.abs(mu) > 0.1) >= 8  # many multipliers far from 0: a real test for the deflation
    return prob, sch, sol.x, memo["krylov_start"]


def _rhs(prob, sch, orbit, con):
    return tuple(np.asarray(a) for a in col.residual(prob.f, prob.args, orbit, con, sch))


@pytest.mark.parametrize("which", ["nearby", "own", "unrelated"])
def test_preconditioned_solve_is_the_dense_direct_solve(ring40, which, monkeypatch):
    """The Newton step at a perturbed orbit of the ring (far from the cycle: a step of size ~0.1): the sparse solve
    preconditioned by the cycle's leading Floquet subspace (a nearby orbit's, as along a branch), by the orbit's own,
    and by random orthonormal columns, each equals the dense condensation's direct solve to 1e-9 of the step."""
    prob, sch, cycle, V_cycle = ring40
    guess = _guess(40, sch, 16, amp=(1.1, 0.9), twist=0.5)
    con = col.natural_constraint(guess, LAM)
    rc, rper, rs = _rhs(prob, sch, guess, con)
    exact = DenseCondensation().bind(prob, sch).linearise(guess, con).solve(-rc, -rper, -rs).to_flat()
    scale = float(jnp.max(jnp.abs(exact)))
    assert scale > 1e-2
    solver = SparseSweep(gmres_rtol=1e-12).bind(prob, sch)
    lin = solver.linearise(guess, con)
    if which == "nearby":
        V = V_cycle
    elif which == "own":
        memo = {}
        BlockKrylov(k=16).multipliers(lin, memo)
        V = memo["krylov_start"]
    else:
        V = np.linalg.qr(np.random.default_rng(3).standard_normal((prob.n, 12)))[0]
    lin.preconditioner = NewtonPicard.build(lin, V)
    assert lin.preconditioner is not None
    d = lin.solve(-rc, -rper, -rs).to_flat()
    assert float(jnp.max(jnp.abs(d - exact))) < 1e-9 * scale


@pytest.mark.parametrize("rtol", [1e-3, 1e-6])
def test_the_leading_subspace_cuts_the_iterations(ring40, rtol, monkeypatch):
    """Solved to the same tolerance (those of Newton steps), the step at the perturbed orbit needs at most half the
    GMRES products with the nearby cycle's leading subspace: the slow diffusion modes (1 - mu close to 0) are
    what plain GMRES spends its iterations on (measured 6 -> 3 and 12 -> 6; at 1e-10, 15 -> 9, the multipliers
    0.33 and below outside the subspace then taking their share).  Counted products, not time."""
    prob, sch, _, V = ring40
    guess = _guess(40, sch, 16, amp=(1.1, 0.9), twist=0.5)
    con = col.natural_constraint(guess, LAM)
    rc, rper, rs = _rhs(prob, sch, guess, con)
    count = _Count(monkeypatch)
    lin = SparseSweep(gmres_rtol=rtol).bind(prob, sch).linearise(guess, con)
    lin.solve(-rc, -rper, -rs)
    plain, count.products = count.products, 0
    lin.preconditioner = NewtonPicard.build(lin, V)
    lin.solve(-rc, -rper, -rs)
    assert count.products <= plain // 2, (count.products, plain)


def test_a_basis_that_does_not_fit_builds_no_preconditioner(ring40):
    prob, sch, cycle, V = ring40
    lin = SparseSweep().bind(prob, sch).linearise(cycle)
    assert NewtonPicard.build(lin, None) is None
    assert NewtonPicard.build(lin, V[:-2]) is None  # another state count (a branch of another problem)
    assert NewtonPicard.build(lin, V[:, :0]) is None
    assert NewtonPicard.build(lin, np.full_like(V, np.nan)) is None  # a failed analysis's basis


def test_deflate_must_be_a_bool():
    with pytest.raises(ValueError, match="deflate must be True or False"):
        SparseSweep(deflate=1)


def test_branches_with_and_without_deflation_agree(monkeypatch):
    """A branch of the ring (n = 48, sparse solver, the block Krylov multipliers) with the default Newton-Picard
    preconditioning and without: the same points, multipliers and special points, in fewer GMRES products."""
    k = 24
    prob, sch = _ring_problem(k), cont.Scheme(4)
    guess = _guess(k, sch, 12, amp=(1.0, 1.0), twist=0.2)
    count = _Count(monkeypatch)
    out, products = {}, {}
    for deflate in (False, True):
        count.products = 0
        s = cont.CycleSettings(m=4, N=12, ds=0.05, ds_max=0.05, max_points=8,
                               linear_solver=SparseSweep(deflate=deflate), floquet=BlockKrylov(k=8))
        out[deflate] = cont.continue_cycles(prob, s, cont.CycleStart(guess))
        products[deflate] = count.products
        assert len(out[deflate]) == 8, out[deflate].message
    np.testing.assert_allclose(out[True].lam, out[False].lam, atol=1e-9)
    np.testing.assert_allclose(out[True].l2, out[False].l2, atol=1e-9)
    np.testing.assert_allclose(out[True].multipliers, out[False].multipliers, atol=1e-8)
    assert [s.type for s in out[True].special] == [s.type for s in out[False].special]
    assert products[True] < products[False], products
