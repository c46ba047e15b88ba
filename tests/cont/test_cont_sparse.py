"""The sparse linear solver (``cont.SparseSweep``) (per-interval sparse LU, GMRES, Arnoldi) against analytic
Floquet multipliers and against the dense condensation, on a ring of diffusively coupled Stuart-Landau oscillators.

Ring of K oscillators z_k' = (lam + i w) z_k - |z_k|^2 z_k + D (z_{k+1} - 2 z_k + z_{k-1}): the synchronous cycle
z_k = sqrt(lam) e^{i w t} has period T = 2 pi / w and, per Fourier mode q = 0..K-1 of the perturbation with
d_q = 4 D sin^2(pi q / K), the multipliers exp(-(2 lam + d_q) T) (amplitude) and exp(-d_q T) (phase).  The
Jacobian is sparse (each oscillator couples to its two neighbours), so the problem can carry its pattern.
"""
import numpy as np
import jax.numpy as jnp
import pytest

from gfbjax import cont
from gfbjax.cont import _collocation as col
from gfbjax.cont import Arnoldi, DenseCondensation, PeriodicQR, SparseSweep, bind_solver
from gfbjax.cont._sparse import SparseCollocation
from gfbjax.cont._sparsity import color_pattern, jacobian_values

from cont_systems import ring, ring_pattern

K, LAM, W, D = 80, 0.5, 2 * np.pi, 1.0


def analytic_multipliers(k, lam, w, d):
    T = 2 * np.pi / w
    dq = 4 * d * np.sin(np.pi * np.arange(k) / k) ** 2
    mu = np.concatenate([np.exp(-(2 * lam + dq) * T), np.exp(-dq * T)])
    return np.sort(mu)[::-1]


@pytest.fixture(scope="module")
def setup():
    args = jnp.array([W, D])
    prob = cont.CycleProblem(f=ring, n=2 * K, args=args, jac_sparsity=ring_pattern(K))
    sch = cont.Scheme(4)
    r = np.sqrt(LAM)
    phase = 0.3 * np.sin(2 * np.pi * np.arange(K) / K)  # a perturbed guess: not synchronous

    def x_of_t(t):
        th = 2 * np.pi * t[:, None] + phase[None, :]
        return np.stack([1.05 * r * np.cos(th), 0.95 * r * np.sin(th)], axis=2).reshape(len(t), -1)

    guess = col.orbit_from_function(x_of_t, 1.02 * 2 * np.pi / W, LAM, sch, col.uniform_mesh(20))
    return prob, sch, guess


def test_coloring_recovers_jacobian(setup):
    prob, _, guess = setup
    x = guess.xm[3]
    c = color_pattern(prob.jac_sparsity)
    assert c.n_colors < prob.n // 10
    J = np.asarray(__import__("jax").jacfwd(lambda y: ring(y, jnp.asarray(LAM), prob.args))(x))
    vals = np.asarray(jacobian_values(lambda y: ring(y, jnp.asarray(LAM), prob.args), x, c))
    np.testing.assert_allclose(vals, J[c.rows, c.cols], rtol=0, atol=1e-13)
    outside = np.ones_like(J, bool)
    outside[c.rows, c.cols] = False
    assert np.all(J[outside] == 0.0)


def test_sparse_newton_step_equals_dense(setup):
    prob, sch, guess = setup
    con = col.natural_constraint(guess, LAM)
    rc, rper, rs = (np.asarray(a) for a in col.residual(prob.f, prob.args, guess, con, sch))
    d_dense = DenseCondensation().bind(prob, sch).linearise(guess, con).solve(-rc, -rper, -rs)
    sp = SparseSweep(gmres_rtol=1e-12).bind(prob, sch)
    d_sparse = sp.linearise(guess, con).solve(-rc, -rper, -rs)
    scale = float(jnp.max(jnp.abs(d_dense.to_flat())))
    assert scale > 1e-3  # the guess is far enough from the cycle for a real test
    assert float(jnp.max(jnp.abs(d_sparse.to_flat() - d_dense.to_flat()))) < 1e-9 * scale


def test_sparse_cycle_and_multipliers_analytic(setup):
    prob, sch, guess = setup
    settings = cont.CycleSettings(newton_tol=1e-10, newton_step_tol=1e-10)
    backend = bind_solver(prob, sch, settings)  # auto: n = 160 with a pattern -> sparse
    assert isinstance(backend, SparseCollocation)
    res, lin = backend.correct(guess, col.natural_constraint(guess, LAM), settings.newton)
    assert res.converged, res.outcome
    o = res.x
    assert float(o.T) == pytest.approx(2 * np.pi / W, rel=1e-9)
    radius = np.sqrt(np.asarray(o.xm)[:, 0::2] ** 2 + np.asarray(o.xm)[:, 1::2] ** 2)
    np.testing.assert_allclose(radius, np.sqrt(LAM), atol=1e-7)
    an = cont.analyse(prob, lin, Arnoldi(k=12))
    mu, stable, terr = an["spectrum"], an["stable"], an["trivial_error"]
    assert len(mu) == 12
    exact = analytic_multipliers(K, LAM, W, D)[: len(mu)]
    np.testing.assert_allclose(np.sort(np.abs(mu))[::-1], exact, atol=1e-7)
    assert np.max(np.abs(mu.imag)) < 1e-7
    assert terr < 1e-9 and stable
    # the dense condensation at the same orbit: the same leading multipliers
    mu_dense = PeriodicQR().multipliers(DenseCondensation().bind(prob, sch).linearise(o), {})
    np.testing.assert_allclose(np.abs(mu_dense[: len(mu)]), np.abs(mu), atol=1e-9)


def test_sparse_and_dense_branches_agree():
    k = 24  # a smaller ring: the dense condensation's cost grows as n^3
    prob = cont.CycleProblem(f=ring, n=2 * k, args=jnp.array([W, D]), jac_sparsity=ring_pattern(k))
    sch = cont.Scheme(4)
    r = np.sqrt(LAM)

    def x_of_t(t):
        th = 2 * np.pi * t[:, None] + 0.2 * np.sin(2 * np.pi * np.arange(k) / k)[None, :]
        return np.stack([r * np.cos(th), r * np.sin(th)], axis=2).reshape(len(t), -1)

    guess = col.orbit_from_function(x_of_t, 2 * np.pi / W, LAM, sch, col.uniform_mesh(12))
    out = {}
    for name, solver, floquet in (("dense", DenseCondensation(), None), ("sparse", SparseSweep(), Arnoldi(k=6))):
        s = cont.CycleSettings(m=4, N=12, ds=0.05, ds_max=0.05, max_points=4, linear_solver=solver,
                               floquet=floquet)
        b = cont.continue_cycles(prob, s, cont.CycleStart(guess))
        assert len(b) == 4, b.message
        out[name] = b
    np.testing.assert_allclose(out["sparse"].lam, out["dense"].lam, atol=1e-9)
    np.testing.assert_allclose(out["sparse"].l2, out["dense"].l2, atol=1e-9)
    np.testing.assert_allclose(np.abs(out["sparse"].multipliers), np.abs(out["dense"].multipliers[:, :6]),
                               atol=1e-8)


def test_sparse_requires_pattern(setup):
    prob, sch, _ = setup
    with pytest.raises(ValueError, match="jac_sparsity"):
        cont.CycleProblem(f=ring, n=prob.n, args=prob.args, jac_sparsity=np.ones((3, 3), bool))
    bare = cont.CycleProblem(f=ring, n=prob.n, args=prob.args)
    with pytest.raises(ValueError, match="jac_sparsity"):
        bind_solver(bare, sch, cont.CycleSettings(linear_solver=SparseSweep()))
    with pytest.raises(ValueError, match="linear_solver"):
        cont.CycleSettings(linear_solver="banded")


def test_sparse_without_pattern_raises_before_continuing(setup):
    _, sch, guess = setup
    bare = cont.CycleProblem(f=ring, n=2 * K, args=jnp.array([W, D]))
    with pytest.raises(ValueError, match="jac_sparsity"):
        cont.continue_cycles(bare, cont.CycleSettings(linear_solver=SparseSweep(), max_points=2), cont.CycleStart(guess))


@pytest.mark.parametrize("drop", ["coupling", "one entry"])
def test_a_pattern_that_misses_entries_of_the_jacobian_is_refused_at_the_first_linearisation(drop):
    """A new user's audit: a ring whose pattern left out the coupling (block-diagonal) was accepted; Newton still
    converged on the exact residual, but the multipliers built from the pattern's Jacobian were 1, 1, 1, 1
    (analytic: 1, 0.023, 0.023, 0.0019, ...), stable cycles were labelled unstable and spurious BPCs reported.
    The first linearisation now compares the pattern's J v with the exact one and names the missing entries,
    before any continuation step; the full pattern passes."""
    k = 4
    pattern = ring_pattern(k)
    if drop == "coupling":
        pattern = np.kron(np.eye(k, dtype=bool), np.ones((2, 2), bool))
    else:
        pattern[0, 2] = False  # oscillator 0's x against oscillator 1's x: the coupling D
    st = cont.CycleSettings(m=4, N=10, ds=0.05, lam_min=0.5, lam_max=1.0, max_points=3, linear_solver=SparseSweep())
    r = np.sqrt(LAM)
    xt = lambda t: r * np.tile(np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)], 1), (1, k))
    start = cont.start_from_function(xt, 2 * np.pi / W, LAM, st)
    bad = cont.CycleProblem(f=ring, n=2 * k, args=jnp.array([W, D]), jac_sparsity=pattern)
    with pytest.raises(ValueError, match=r"jac_sparsity leaves out non-zero entries of df/dx .*\(0, 2\) = 1"):
        cont.continue_cycles(bad, st, start)
    good = cont.CycleProblem(f=ring, n=2 * k, args=jnp.array([W, D]), jac_sparsity=ring_pattern(k))
    br = cont.continue_cycles(good, st, start)
    assert len(br) == 3 and br.stable.all()


def _small_ring():
    k = 6
    prob = cont.CycleProblem(f=ring, n=2 * k, args=jnp.array([W, D]), jac_sparsity=ring_pattern(k))
    sch = cont.Scheme(3)
    r = np.sqrt(LAM)

    def x_of_t(t):
        th = 2 * np.pi * t[:, None] + 0.2 * np.sin(2 * np.pi * np.arange(k) / k)[None, :]
        return np.stack([1.1 * r * np.cos(th), 0.9 * r * np.sin(th)], axis=2).reshape(len(t), -1)

    orbit = col.orbit_from_function(x_of_t, 1.03 * 2 * np.pi / W, LAM, sch, col.uniform_mesh(5))
    return prob, sch, orbit


def test_transposed_solves_equal_the_explicit_transpose():
    """J^T lam = g on both solvers against a dense solve with the explicitly formed Jacobian (jax.jacfwd of the
    flattened residual), at an orbit off the solution and with a random pseudo-arclength row."""
    prob, sch, o = _small_ring()
    rng = np.random.default_rng(0)
    flat = o.to_flat()
    v = o.from_flat(jnp.asarray(rng.normal(size=flat.shape)))
    con = col.palc_constraint(o, v, 0.01, ref=o)
    J = np.asarray(col.dense_jacobian(prob.f, prob.args, o, con, sch))
    g = o.from_flat(jnp.asarray(rng.normal(size=flat.shape)))
    ref = np.linalg.solve(J.T, np.asarray(g.to_flat()))
    N, m, n = o.N, sch.m, o.n
    for solver in (DenseCondensation(), SparseSweep(gmres_rtol=1e-13)):
        lam_c, lam_per, lam_s = solver.bind(prob, sch).linearise(o, con).solve_transpose(g)
        got = np.concatenate([np.ravel(lam_c), lam_per, lam_s])
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9 * np.max(np.abs(ref)), err_msg=solver.name)
        assert np.asarray(lam_c).shape == (N, m, n)


def test_adjoint_gradients_agree_on_both_solvers():
    """d(period)/d(args) and d|mu_1|/d(args) at a converged ring cycle: the adjoint on the sparse solver equals the
    dense one and the tangent mode, and the period's derivative equals the analytic d(2 pi / w)/dw."""
    prob, sch, o = _small_ring()
    period = lambda orbit, args: orbit.T  # noqa: E731
    grads, mus = {}, {}
    for solver in (DenseCondensation(), SparseSweep(gmres_rtol=1e-13)):
        s = cont.CycleSettings(m=3, newton_tol=1e-11, newton_step_tol=1e-11, linear_solver=solver)
        sol, lin = cont.correct_cycle(prob, o, settings=s)
        assert sol.converged
        grads[solver.name] = np.asarray(cont.adjoint_gradient(prob, lin, sch, period))
        mu, gm = cont.multiplier_gradient(prob, lin, sch)
        mus[solver.name] = (mu, np.asarray(gm))
        dargs = [jnp.array([1.0, 0.0]), jnp.array([0.0, 1.0])]
        tangents = cont.orbit_sensitivities(prob, lin, dargs, sch)
        mu_t, dmu = cont.multiplier_derivatives(prob, lin, sch, tangents, dargs)
        tangent_mod = np.array([np.real(np.conj(mu_t) * d) / abs(mu_t) for d in dmu])
        np.testing.assert_allclose(np.asarray(gm), tangent_mod, rtol=1e-7, atol=1e-10, err_msg=solver.name)
    # central differences of the discrete period (the collocation's own T, 5 intervals of degree 3)
    fd = []
    for i in range(2):
        Ts = []
        for h in (1e-5, -1e-5):
            args = prob.args.at[i].add(h)
            p2 = cont.CycleProblem(f=ring, n=prob.n, args=args, jac_sparsity=prob.jac_sparsity)
            sol, _ = cont.correct_cycle(p2, o, settings=cont.CycleSettings(m=3, newton_tol=1e-12,
                                                                            newton_step_tol=1e-12))
            Ts.append(float(sol.x.T))
        fd.append((Ts[0] - Ts[1]) / 2e-5)
    np.testing.assert_allclose(grads["dense"], fd, rtol=1e-6, atol=1e-9)
    # and the continuous limit T = 2 pi / w (discretisation error O(h^6) ~ 1e-4 here); D does not change T
    np.testing.assert_allclose(grads["dense"][0], -2 * np.pi / W ** 2, rtol=2e-4)
    np.testing.assert_allclose(grads["dense"][1], 0.0, atol=1e-9)
    np.testing.assert_allclose(grads["sparse"], grads["dense"], rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(mus["sparse"][1], mus["dense"][1], rtol=1e-7, atol=1e-10)


# ---------------------------------------------------------------- block Krylov multipliers, inexact and chord Newton
def test_block_krylov_multipliers_analytic(setup):
    """BlockKrylov (the sparse default) on the ring, whose multipliers come in equal pairs (modes q and K - q):
    the ones at or outside ``inside`` to 1e-9 of the closed form, the rest to their looser residual tolerance;
    the same as ARPACK's."""
    prob, sch, guess = setup
    settings = cont.CycleSettings(newton_tol=1e-10, newton_step_tol=1e-10)
    res, lin = bind_solver(prob, sch, settings).correct(guess, col.natural_constraint(guess, LAM), settings.newton)
    assert res.converged
    mu = cont.BlockKrylov(k=12).multipliers(lin, {})
    assert len(mu) >= 12 and abs(mu[-1]) < 0.9
    exact = analytic_multipliers(K, LAM, W, D)[: len(mu)]
    got = np.sort(np.abs(mu))[::-1]
    outside = exact >= 0.9
    assert outside.sum() >= 5  # the test covers the tight tolerance, pairs included
    np.testing.assert_allclose(got[outside], exact[outside], atol=1e-9)
    np.testing.assert_allclose(got, exact, atol=1e-5)
    arpack = Arnoldi(k=len(mu)).multipliers(lin, {})
    np.testing.assert_allclose(np.abs(arpack[: outside.sum()]), got[outside], atol=1e-9)


def test_block_product_equals_single_products(setup):
    prob, sch, guess = setup
    lin = SparseSweep().bind(prob, sch).linearise(guess)
    V = np.random.default_rng(1).standard_normal((prob.n, 5))
    single = np.stack([lin.monodromy_matvec(V[:, i]) for i in range(5)], axis=1)
    np.testing.assert_allclose(lin.monodromy_matmat(V), single, rtol=0, atol=1e-12 * np.max(np.abs(single)))


def _operator(eigs, n, seed=0):
    """A real n x n matrix with the given leading eigenvalues (a complex value brings its conjugate) and the
    rest uniformly in [0, 0.2), in a random, non-orthogonal basis."""
    rng = np.random.default_rng(seed)
    B = np.zeros((n, n))
    i = 0
    for e in eigs:
        if np.iscomplex(e):
            B[i:i + 2, i:i + 2] = [[e.real, e.imag], [-e.imag, e.real]]
            i += 2
        else:
            B[i, i] = e
            i += 1
    B[i:, i:] = np.diag(rng.uniform(0.0, 0.2, n - i))
    S = np.eye(n) + 0.3 * rng.standard_normal((n, n)) / np.sqrt(n)
    return S @ B @ np.linalg.inv(S)


def test_krylov_keeps_a_complex_pair_together_at_the_cut():
    """k = 3 would cut the pair 0.5 +- 0.2i: both members are returned, never one (which would read as real)."""
    from gfbjax.cont._floquet import krylov_leading
    A = _operator([1.0, 0.95, 0.5 + 0.2j], 60)
    mu, _ = krylov_leading(lambda V: A @ V, 60, k=3, inside=0.9, tol=1e-11, tol_inside=1e-11, block=4, max_dim=60)
    np.testing.assert_allclose(np.sort_complex(mu), np.sort_complex([0.5 - 0.2j, 0.5 + 0.2j, 0.95, 1.0]), atol=1e-9)


def test_krylov_returns_past_every_multiplier_outside_inside():
    """Seven multipliers at or outside 0.9 with k = 4: k doubles until the smallest returned is inside 0.9."""
    from gfbjax.cont._floquet import krylov_leading
    lead = [1.3, 1.1 + 0.3j, 1.0, 0.97 + 0.1j, 0.92, 0.6]
    A = _operator(lead, 80, seed=3)
    mu, _ = krylov_leading(lambda V: A @ V, 80, k=4, inside=0.9, tol=1e-11, tol_inside=1e-11, block=4, max_dim=80)
    assert abs(mu[-1]) < 0.9 and len(mu) == 8
    np.testing.assert_allclose(np.sort_complex(mu[:7]), np.sort_complex(
        [1.3, 1.1 + 0.3j, 1.1 - 0.3j, 1.0, 0.97 + 0.1j, 0.97 - 0.1j, 0.92]), atol=1e-9)


def test_krylov_without_convergence_in_max_dim_gives_none():
    from gfbjax.cont._floquet import krylov_leading
    A = _operator([1.0, 0.95, 0.9 + 0.1j], 80, seed=5)
    assert krylov_leading(lambda V: A @ V, 80, k=4, inside=0.9, tol=1e-14, tol_inside=1e-14, block=2,
                          max_dim=4) is None


def test_inexact_chord_newton_converges_to_the_exact_newton_orbit(setup, monkeypatch):
    """The default sparse corrector (GMRES to a tolerance that follows the residual, factorisations reused while
    the residual falls) converges to the same orbit as exact Newton (a factorisation and a full GMRES solve at
    every step), with fewer factorisations, and leaves the converged orbit its own linearisation."""
    prob, sch, guess = setup
    con = col.natural_constraint(guess, LAM)
    newton = cont.NewtonSettings(tol=1e-10, atol_step=1e-10, rtol_step=1e-10, max_iter=12)
    counts = {}
    real = SparseCollocation.linearise

    def counting(self, orbit, c=None):
        counts[self.settings.chord] = counts.get(self.settings.chord, 0) + 1
        return real(self, orbit, c)

    monkeypatch.setattr(SparseCollocation, "linearise", counting)
    exact, _ = SparseSweep(chord=0.0, gmres_forcing=1e-11).bind(prob, sch).correct(guess, con, newton)
    fast, lin = SparseSweep().bind(prob, sch).correct(guess, con, newton)
    assert exact.converged and fast.converged
    assert float(jnp.max(jnp.abs(fast.x.to_flat() - exact.x.to_flat()))) < 1e-9
    assert counts[SparseSweep().chord] < counts[0.0]
    assert float(jnp.max(jnp.abs(lin.orbit.to_flat() - fast.x.to_flat()))) == 0.0
    np.testing.assert_allclose(np.asarray(fast.aux.to_flat()), np.asarray(exact.aux.to_flat()), atol=1e-8)


def test_blocks_factorised_in_a_given_column_order_solve_exactly():
    """Every interval block shares one pattern, so the sparse solver computes SuperLU's column order once, from the
    first block, and factorises the others in it (``_PermutedLU``, their values permuted into that order): the
    solves with K and K^T are exact for every block, the fill is that of SuperLU's own ordering, and a singular
    block is named by its interval."""
    import types

    import scipy.sparse as sps
    import scipy.sparse.linalg as spla
    from gfbjax.cont import _sparse
    from gfbjax.cont._newton import LinearSolveError
    rng = np.random.default_rng(2)
    A = (sps.random(300, 300, density=0.02, random_state=3) + 3 * sps.eye(300)).tocsc()
    A.sort_indices()
    blocks = [A.copy() for _ in range(5)]
    for K in blocks[1:]:
        K.data = K.data * rng.uniform(0.5, 2.0, K.nnz)
    solver = types.SimpleNamespace(scheme=types.SimpleNamespace(m=3), n=100,
                                   settings=types.SimpleNamespace(permc_spec="COLAMD"), _order=None, _KP=None,
                                   _K_indices=A.indices, _K_indptr=A.indptr)
    factorise = lambda Kd: _sparse.SparseCollocation._factorise_all(solver, Kd)
    lus = factorise(np.stack([K.data for K in blocks]))
    b, B = rng.standard_normal(300), rng.standard_normal((300, 4))
    for K, lu in zip(blocks, lus):
        assert np.max(np.abs(K @ lu.solve(b) - b)) < 1e-12
        assert np.max(np.abs(K @ lu.solve(B) - B)) < 1e-12
        assert np.max(np.abs(K.T @ lu.solve(b, trans="T") - b)) < 1e-12
    # a later linearisation factorises every block in the first one's order, with the fill of SuperLU's own
    Kd = np.stack([K.data for K in blocks])
    again = factorise(Kd)
    own = spla.splu(blocks[0], permc_spec="COLAMD")
    assert isinstance(again[0], _sparse._PermutedLU)
    assert again[0].lu.L.nnz + again[0].lu.U.nnz == own.L.nnz + own.U.nnz
    assert np.max(np.abs(blocks[0] @ again[0].solve(b) - b)) < 1e-12
    # an exactly singular block (a zero column) is refused, by its interval
    Kd[3, A.indptr[7]:A.indptr[8]] = 0.0
    with pytest.raises(LinearSolveError, match="interval 3"):
        factorise(Kd)


def test_krylov_warm_start_finds_a_multiplier_outside_its_basis():
    """A multiplier that grows past all others with an eigenvector outside the previous point's Ritz basis (review
    case): the warm start converges at once to what its basis holds, so without enough random directions the new
    leading value 1.05 was missed while every returned value passed its residual test."""
    from gfbjax.cont._floquet import krylov_leading
    rng = np.random.default_rng(5)
    n = 200
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    ev = np.concatenate([[1.0], np.linspace(0.95, 0.5, 11), np.full(n - 12, 0.01)])
    kw = dict(k=12, inside=0.9, tol=1e-11, tol_inside=1e-6, block=16, max_dim=n)
    _, basis = krylov_leading(lambda V: Q @ (ev[:, None] * (Q.T @ V)), n, **kw)
    ev2 = ev.copy()
    ev2[100] = 1.05
    mu, _ = krylov_leading(lambda V: Q @ (ev2[:, None] * (Q.T @ V)), n, start=basis, **kw)
    np.testing.assert_allclose(mu.real, np.sort(ev2)[::-1][:12], atol=1e-9)


def test_krylov_warm_start_from_nearly_exact_vectors_converges_without_the_whole_space():
    """Review of session 18: a warm start from the last point's Floquet vectors, exact to ~1e-11, whose products
    add parts below 1e-10 to the space.  Those parts were dropped as numerically inside it, and they were all the
    leading pairs still lacked for their tolerance (1e-11): the space grew to all n columns (on the GFB at the NS
    point 433 columns, where a cold start needs 176).  Now parts down to a tenth of the tolerance are kept, and
    the warm start costs no more than a cold start and one block."""
    from gfbjax.cont._floquet import krylov_leading
    rng = np.random.default_rng(7)
    n = 200
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    ev = np.concatenate([[1.4, 1.0], np.linspace(0.8, 0.3, 10), 0.1 * rng.uniform(0.5, 1.0, n - 12)])
    M = Q @ np.diag(ev) @ Q.T
    cols = [0]

    def matmat(V):
        cols[0] += V.shape[1]
        return M @ V

    kw = dict(k=12, inside=0.9, tol=1e-11, tol_inside=1e-6, block=16, max_dim=n)
    krylov_leading(matmat, n, **kw)
    cold, cols[0] = cols[0], 0
    start = np.linalg.qr(Q[:, :12] + 1e-11 * rng.standard_normal((n, 12)))[0]
    mu, _ = krylov_leading(matmat, n, start=start, **kw)
    assert cols[0] <= cold + 16 < n
    np.testing.assert_allclose(mu.real, ev[:12], atol=1e-10)
    np.testing.assert_allclose(mu.imag, 0.0, atol=1e-10)


def test_krylov_stops_early_when_the_rest_of_the_spectrum_is_damped_to_zero():
    """Radau points damp the stiff film modes to |mu| ~ 1e-10 and below. Relative digits of such multipliers
    cannot be had (their Ritz residuals sit at rounding level of ||M||), so the space grew to n at every point,
    5x the cost of the Gauss branch's multipliers. Below modulus 1e-3 the residual is measured against 1e-3: the
    leading multipliers come out exact, the tiny ones within 1e-9 absolute, from a fraction of the space."""
    from gfbjax.cont._floquet import krylov_leading
    rng = np.random.default_rng(7)
    n = 300
    lead = np.array([1.0, 0.85, 0.6, 0.35, 0.03])
    ev = np.concatenate([lead, 10.0 ** rng.uniform(-16, -9, n - len(lead))])
    S = np.eye(n) + 0.3 * rng.standard_normal((n, n)) / np.sqrt(n)  # non-normal, as a monodromy matrix is
    A = S @ np.diag(ev) @ np.linalg.inv(S)
    used = []

    def matmat(V):
        used.append(V.shape[1])
        return A @ V

    mu, _ = krylov_leading(matmat, n, k=12, inside=0.9, tol=1e-11, tol_inside=1e-6, block=16, max_dim=n)
    np.testing.assert_allclose(np.abs(mu[:5]), lead, rtol=1e-9)
    assert np.all(np.abs(mu[5:]) < 1e-8)
    assert sum(used) <= n // 3, used


def test_krylov_returns_a_set_closed_under_conjugation_with_a_repeated_pair():
    """Two equal pairs p, conj(p), p, conj(p): a cut after the first pair is already closed and must not take one
    member of the second (review case: [1, p, conj(p), p] was returned)."""
    from gfbjax.cont._floquet import _wanted, krylov_leading
    p = 0.5 + 0.6j
    assert _wanted(np.array([1, p, np.conj(p), p, np.conj(p), 0.1]), 3, 0.9) == 3
    assert _wanted(np.array([1, p, np.conj(p), p, np.conj(p), 0.1]), 2, 0.9) == 3
    rot = 0.8 * np.array([[np.cos(0.7), -np.sin(0.7)], [np.sin(0.7), np.cos(0.7)]])
    n = 40
    rng = np.random.default_rng(1)
    B = np.diag(np.concatenate([[1.0, 0.99], np.zeros(4), 0.3 * rng.random(n - 6)]))
    B[2:4, 2:4] = rot
    B[4:6, 4:6] = rot
    S = rng.standard_normal((n, n))
    A = S @ B @ np.linalg.inv(S)
    for k in (2, 3, 4, 5):
        mu, _ = krylov_leading(lambda V: A @ V, n, k=k, inside=0.9, tol=1e-11, tol_inside=1e-6, block=4, max_dim=n)
        assert abs(np.sum(mu).imag) < 1e-8, (k, mu)


def test_chord_steps_cost_no_iteration_that_exact_newton_would_not_take():
    """A slow correction from a poor guess (review case: ring K = 10, weak coupling, 30 % amplitude distortion and
    1.1 T) that exact Newton finishes in the default 8 iterations: the last steps of the budget are full Newton
    steps, so the default corrector finishes too, on the same orbit."""
    k = 10
    prob = cont.CycleProblem(f=ring, n=2 * k, args=jnp.array([W, 0.05]), jac_sparsity=ring_pattern(k))
    sch = cont.Scheme(4)
    r, phase = np.sqrt(LAM), 0.3 * np.sin(2 * np.pi * np.arange(k) / k)

    def x_of_t(t):
        th = 2 * np.pi * t[:, None] + phase[None, :]
        return np.stack([1.3 * r * np.cos(th), 0.7 * r * np.sin(th)], axis=2).reshape(len(t), -1)

    guess = col.orbit_from_function(x_of_t, 1.1 * 2 * np.pi / W, LAM, sch, col.uniform_mesh(20))
    con = col.natural_constraint(guess, LAM)
    newton = cont.CycleSettings().newton
    assert newton.max_iter == 8
    exact, _ = SparseSweep(chord=0.0, gmres_forcing=1e-11).bind(prob, sch).correct(guess, con, newton)
    fast, _ = SparseSweep().bind(prob, sch).correct(guess, con, newton)
    assert exact.converged and int(exact.iterations) >= 7  # a slow solve: the budget matters
    assert fast.converged, fast.outcome
    assert float(jnp.max(jnp.abs(fast.x.to_flat() - exact.x.to_flat()))) < 1e-9
