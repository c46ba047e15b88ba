"""Mesh adaptation and the a-posteriori mesh error (trust issue, cases d and e).

d. r' = r (1 - r^2), theta' = lam - cos(theta): stable cycles of period 2 pi / sqrt(lam^2 - 1), none for
   lam <= 1.  Continued down from lam = 2 towards the infinite-period limit.
e. x'' + 0.1 x' + x + 3 max(x - 0.5, 0) = 0.1 cos(omega t): folds of the resonance curve at omega =
   1.0805948052 and 1.1445435815 (shooting with the kink located as an event, issue 12).
"""
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gfbjax.cont import (CycleProblem, CycleSettings, continue_cycles, correct_cycle, multipliers_product,
                         start_from_function, start_from_samples)
from gfbjax.cont import _collocation as col
from gfbjax.cont._mesh import defect_errors, error_estimate, interval_errors, remesh


def snic(x, lam, args):
    r2 = x[0] ** 2 + x[1] ** 2
    th = lam - x[0] / jnp.sqrt(r2)  # theta' = lam - cos(theta)
    return jnp.array([x[0] * (1 - r2) - x[1] * th, x[1] * (1 - r2) + x[0] * th])


def _snic_start(st, lam0=2.0):
    T0 = 2 * np.pi / np.sqrt(lam0 ** 2 - 1)
    w = np.sqrt(lam0 ** 2 - 1)

    def x_of_t(t):  # the exact cycle: tan(theta/2) = sqrt((lam+1)/(lam-1)) tan(w t / 2)
        th = 2 * np.arctan(np.sqrt((lam0 + 1) / (lam0 - 1)) * np.tan(w * t * T0 / 2))
        return np.stack([np.cos(th), np.sin(th)], -1)
    return start_from_function(x_of_t, T0, lam0, st)


def _snic_branch(adapt, points):
    st = CycleSettings(m=4, N=20, ds=0.1, ds_max=1.0, direction=-1, lam_min=0.9, lam_max=2.5, max_points=points,
                       save_states=True, adapt=adapt)
    return continue_cycles(CycleProblem(snic, 2), st, _snic_start(st))


@pytest.fixture(scope="module")
def adapted():
    return _snic_branch(3, 150)


def test_infinite_period_limit_with_adaptive_mesh(adapted):
    br = adapted
    T_exact = 2 * np.pi / np.sqrt(br.lam ** 2 - 1)
    assert br.period[-1] > 140 and np.all(br.lam > 1.0)  # far into the limit, and never past it
    np.testing.assert_allclose(br.period, T_exact, rtol=2e-6)
    assert np.all(br.stable) and np.max(br.trivial_error) < 1e-4


def test_fixed_mesh_loses_the_period_and_says_so():
    """The same branch on the uniform mesh: period errors above 1e-4 from T ~ 70 (the issue's 'before'), and the
    points are flagged."""
    br = _snic_branch(0, 75)
    T_exact = 2 * np.pi / np.sqrt(br.lam ** 2 - 1)
    err = np.abs(br.period - T_exact) / T_exact
    assert np.max(err) > 1e-4
    assert np.all(br.flagged[err > 1e-5])


def _true_error(f, o, sch, args=None, stiff=False):
    """The orbit against a tight time integration from its own first node, max over 16 points per interval
    (``stiff``: an implicit integrator with the exact Jacobian)."""
    t, X = col.evaluate(o, sch, 16)
    lam, T = float(o.lam), float(o.T)
    rhs, jac = jax.jit(f), jax.jit(jax.jacfwd(f))  # compiled once, not traced at every step of the integrator
    opts = dict(method="Radau", rtol=1e-11, jac=lambda tt, x: np.asarray(jac(jnp.asarray(x), lam, args))) \
        if stiff else dict(method="DOP853", rtol=1e-12)
    ref = solve_ivp(lambda tt, x: np.asarray(rhs(jnp.asarray(x), lam, args)), (0, T), X[0], t_eval=t * T,
                    atol=1e-13, **opts).y.T
    return np.max(np.abs(X - ref))


def test_error_estimate_matches_the_true_error(adapted):
    """The estimate against the orbit's true error between its nodes (a tight time integration from the orbit's
    own first node): the interpolation estimate within a factor of 4 either way, the reported one within 1/2 to 4
    (measured 0.69-1.34).  The field is smooth: the defects over whole intervals are far below the interpolation
    estimate."""
    br, sch = adapted, col.Scheme(4)
    for i in (0, 40, 100):
        o = col.Orbit(*(jnp.asarray(br.states[k][i]) for k in ("mesh", "xm", "xi", "T", "lam")))
        true = _true_error(snic, o, sch)
        interp = np.max(interval_errors(o, sch))
        assert true / 4 <= interp <= 4 * true, (i, true, interp)
        assert np.max(np.sum(defect_errors(snic, None, o, sch), axis=0)) < interp / 10  # no kink
        est = error_estimate(o, sch, snic) * (1 + np.max(np.abs(np.asarray(o.xm))))
        assert true / 2 <= est <= 4 * true, (i, true, est)


def kinked_oscillator(z, w, args):
    x, v, u, s = z
    r2 = u * u + s * s
    return jnp.array([v, -0.1 * v - x - 3 * jnp.maximum(x - 0.5, 0.0) + 0.1 * u,
                      u + w * s - u * r2, -w * u + s - s * r2])


FOLDS = (1.0805948052, 1.1445435815)


def _resonance(N, adapt):
    w0 = 0.9
    H = 0.1 / (1 - w0 ** 2 + 0.1j * w0)

    def x_of_t(t):  # the linear response (the kink is not reached at w0)
        e = np.exp(2j * np.pi * t)
        return np.stack([np.real(H * e), np.real(1j * w0 * H * e), e.real, -e.imag], -1)
    st = CycleSettings(m=4, N=N, ds=0.05, ds_max=0.3, lam_min=0.85, lam_max=1.3, max_points=150, adapt=adapt,
                       detect=("LPC",))
    return continue_cycles(CycleProblem(kinked_oscillator, 4), st, start_from_function(x_of_t, 2 * np.pi / w0, w0, st))


@pytest.mark.parametrize("N", [16, 32, 64])
def test_mesh_error_sees_the_kink(N):
    """The kinked oscillator at omega = 1 (x reaches 0.62, past the kink at 0.5) on uniform meshes: the orbit's
    true error (8.6e-4, 2.0e-4, 3.1e-5) against the interpolation estimate alone (3.4e-5, 1.2e-5, 2.6e-6: 25-12x
    short) and the reported estimate, which carries the collocation defects, integrated by a finer quadrature,
    through the linearisation (measured 8.0e-4, 2.0e-4, 2.5e-5)."""
    w0 = 1.0
    H = 0.1 / (1 - w0 ** 2 + 0.1j * w0)

    def x_of_t(t):  # the linear response as the guess
        e = np.exp(2j * np.pi * t)
        return np.stack([np.real(H * e), np.real(1j * w0 * H * e), e.real, -e.imag], -1)
    st = CycleSettings(m=4, N=N)
    guess = start_from_function(x_of_t, 2 * np.pi / w0, w0, st).orbit
    sol, _ = correct_cycle(CycleProblem(kinked_oscillator, 4), guess, settings=st)
    assert sol.converged
    o, sch = sol.x, col.Scheme(4)
    true = _true_error(kinked_oscillator, o, sch)
    scale = 1 + np.max(np.abs(np.asarray(o.xm)))
    assert np.max(interval_errors(o, sch)) < true / 8  # the blind spot the defects cover
    est = error_estimate(o, sch, kinked_oscillator) * scale
    assert true / 2 <= est <= 2 * true, (N, true, est)


def van_der_pol(x, mu, args):
    return jnp.array([x[1], mu * (1 - x[0] ** 2) * x[1] - x[0]])


def _van_der_pol_cycle(mu):
    """(t, x(t), T): one period of the stable van der Pol cycle, from a time integration."""
    rhs = jax.jit(van_der_pol)

    def g(t, x):
        return np.asarray(rhs(jnp.asarray(x), mu, None))
    x0 = solve_ivp(g, (0, 60), [2.0, 0.0], rtol=1e-11, atol=1e-12, method="DOP853").y[:, -1]

    def back(t, x):  # x0[0] again, moving the same way
        return x[0] - x0[0]
    back.direction = float(np.sign(g(0, x0)[0]))
    ev = solve_ivp(g, (0, 40), x0, events=back, rtol=1e-12, atol=1e-13, method="DOP853").t_events[0]
    T = float(ev[ev > 1.0][0])
    tt = np.linspace(0, T, 2000)
    return tt, solve_ivp(g, (0, T), x0, t_eval=tt, rtol=1e-11, atol=1e-12, method="DOP853").y.T, T


@pytest.mark.parametrize("collocation", ["gauss", "radau"])
def test_mesh_error_sees_the_error_between_the_nodes_of_a_barely_resolved_orbit(collocation):
    """Van der Pol at mu = 1 on 16 uniform intervals: the orbit's true error (1.0e-3 with Gauss points, 2.0e-3
    with Radau) lies in the fast stretch, between the nodes.  The interpolation estimate is 2.6x and 7x short with
    this time origin (3.5-15x with others, in a fresh-user review of session 9, where the point went unflagged).
    Propagated through the linearisation, the running defects see it: measured 0.74 and 0.71 of the true error."""
    tt, X, T = _van_der_pol_cycle(1.0)
    st = CycleSettings(m=4, N=16, collocation=collocation)
    sol, lin = correct_cycle(CycleProblem(van_der_pol, 2), start_from_samples(tt, X, T, 1.0, st).orbit, settings=st)
    assert sol.converged
    o, sch = sol.x, col.Scheme(4, collocation)
    true = _true_error(van_der_pol, o, sch)
    assert np.max(interval_errors(o, sch)) < true / 2  # the blind spot
    est = error_estimate(o, sch, van_der_pol, None, lin) * (1 + np.max(np.abs(np.asarray(o.xm))))
    assert true / 2 <= est <= 2 * true, (true, est)


def _distance_to_the_fine_cycle(f, args, o, sch, N=512):
    """The orbit against the same cycle (same lam, the orbit as phase reference) corrected on N intervals, at 16
    points per interval of the orbit."""
    st = CycleSettings(m=sch.m, N=N, collocation=sch.kind)
    fine, _ = correct_cycle(CycleProblem(f, o.n, args), remesh(o, sch, col.uniform_mesh(N)), settings=st)
    assert fine.converged
    t, X = col.evaluate(o, sch, 16)
    mesh = np.asarray(fine.x.mesh)
    j = np.clip(np.searchsorted(mesh, t, side="right") - 1, 0, N - 1)
    ref = np.einsum("ti,tin->tn", sch.basis_at((t - mesh[j]) / (mesh[j + 1] - mesh[j])), np.asarray(fine.x.nodes())[j])
    return np.max(np.abs(X - ref))


@pytest.mark.parametrize("collocation", ["gauss", "radau"])
def test_mesh_error_of_an_unstable_cycle(collocation):
    """Van der Pol at mu = 2 reversed in time: the same closed curve, traversed backwards, with the multiplier
    7.9e7.  A time integration from the orbit's first node amplifies its error by that multiplier (8.7e-3 and 0.76
    for an orbit 7.0e-4 and 1.4e-3 from the exact cycle, N = 32), and so did a first version of the estimate that
    carried the defects that way (135x and 290x the distance; the review of session 10).  Carried by the periodic
    problem they give the distance: measured 0.87 and 0.89."""
    mu = 2.0
    tt, X, T = _van_der_pol_cycle(mu)

    def reversed_field(x, mu, args):
        return -van_der_pol(x, mu, args)
    st = CycleSettings(m=4, N=32, collocation=collocation)
    sol, lin = correct_cycle(CycleProblem(reversed_field, 2), start_from_samples(tt, X[::-1], T, mu, st).orbit,
                             settings=st)
    assert sol.converged
    o, sch = sol.x, col.Scheme(4, collocation)
    assert np.max(np.abs(multipliers_product(lin.transfer_matrices()))) > 1e6
    dist = _distance_to_the_fine_cycle(reversed_field, None, o, sch)
    est = error_estimate(o, sch, reversed_field, None, lin) * (1 + np.max(np.abs(np.asarray(o.xm))))
    assert dist / 2 <= est <= 2 * dist, (dist, est)


def slaved(x, lam, k):
    """A unit-circle oscillator (x0, x1) and a strongly damped component x2' = -k (x2 - x0^3) that follows it."""
    r2 = x[0] ** 2 + x[1] ** 2
    return jnp.array([x[0] * (1 - r2) - lam * x[1], x[1] * (1 - r2) + lam * x[0], -k * (x[2] - x[0] ** 3)])


@pytest.mark.parametrize("m, N, collocation", [(4, 16, "radau"), (2, 32, "radau"), (2, 32, "gauss"),
                                               (4, 32, "gauss")])
def test_mesh_error_of_a_strongly_damped_component(m, N, collocation):
    """k = 1e4, so h k is about 2e3-4e3 on every interval.  The defects of a strongly damped component do not add
    up: its error is its residual divided by its rate.  The summed defects of session 9 were 28x, 1.3e4x and 89x
    the true error in the first three cases (a good point flagged).  With Gauss points the mesh values of such a
    component are the polynomials extrapolated past the last Gauss point, which no defect shows: the
    interpolation estimate was 0.13x and 0.11x the true error in the last two.  Measured now: 0.76, 0.61, 1.02,
    1.00."""
    k = jnp.asarray(1e4)
    st = CycleSettings(m=m, N=N, collocation=collocation)

    def x_of_t(t):  # the slaved component follows x0^3 up to O(1/k)
        return np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t), np.cos(2 * np.pi * t) ** 3], -1)
    sol, lin = correct_cycle(CycleProblem(slaved, 3, k), start_from_function(x_of_t, 2 * np.pi, 1.0, st).orbit,
                             settings=st)
    assert sol.converged
    o, sch = sol.x, col.Scheme(m, collocation)
    true = _true_error(slaved, o, sch, k, stiff=True)
    est = error_estimate(o, sch, slaved, k, lin) * (1 + np.max(np.abs(np.asarray(o.xm))))
    assert true / 2 <= est <= 2 * true, (true, est)


@pytest.mark.slow
def test_kink_folds_adaptive_vs_fixed():
    fixed = _resonance(40, 0)
    lpc = sorted(s.lam for s in fixed.special_of("LPC"))
    assert len(lpc) == 2
    assert abs(lpc[1] - FOLDS[1]) > 5e-5  # the 'before': the kink inside an interval
    _error_estimates_match(fixed)
    adapted = _resonance(40, 3)
    lpc = sorted(s.lam for s in adapted.special_of("LPC"))
    assert len(lpc) == 2  # no spurious folds from re-meshing near the turning points
    np.testing.assert_allclose(lpc, FOLDS, atol=3e-5)
    _error_estimates_match(adapted)


def test_every_fold_reported_at_N_80_covers_a_true_fold():
    """With default settings but N = 80 the second fold comes out as three bracketed LPCs within 2e-5 (1.1445269,
    1.1445437, 1.1445464; session 13, fresh-user review): each mesh adaptation moved a node across the kink and the
    discrete tangent's lam component jumped (+3.1e-3 -> -5.8e-3), a zig-zag of the discrete branch within its own
    error.  Merging such runs was tried and dropped (it hid distinct events whose error bars overlap: three Hopf
    points 1e-3 apart with other frequencies).  What holds: every reported fold lies within its error bar of a
    shooting value, none is called located beyond the true two, and each true fold is reported."""
    w0 = 0.85
    H = 0.1 / (1 - w0 ** 2 + 0.1j * w0)

    def x_of_t(t):
        e = np.exp(2j * np.pi * t)
        return np.stack([np.real(H * e), np.real(1j * w0 * H * e), e.real, -e.imag], -1)
    st = CycleSettings(N=80, lam_min=0.8, lam_max=1.3)
    br = continue_cycles(CycleProblem(kinked_oscillator, 4), st, start_from_function(x_of_t, 2 * np.pi / w0, w0, st))
    lpc = br.special_of("LPC")
    for s in lpc:
        assert min(abs(s.lam - f) for f in FOLDS) <= s.lam_error, (s.lam, s.lam_error)
    assert sum(s.located for s in lpc) <= 2
    for f in FOLDS:
        assert any(abs(s.lam - f) <= s.lam_error for s in lpc), f


def _error_estimates_match(branch):
    """Each fold's estimated error (SpecialPoint.lam_error: the larger move of its zero on the halved and on the
    staggered mesh) at least a quarter of its true error, and at most ten times it.  Before, nothing signalled the
    1e-4 error at the second fold on the fixed mesh: the orbit's mesh estimate is ~1e-5 and the trivial
    multiplier exact to 1e-14.  Measured, true vs estimate: 1.4e-5 vs 1.3e-5, 1.0e-4 vs 7.7e-5 on the fixed mesh;
    2.7e-7 vs 1.1e-6, 1.6e-5 vs 9.6e-6 adapted.  The upper bound was 4 while the estimate came from the halved
    mesh alone; the larger of two moves is conservative by design (see the next test), and only the lower bound
    decides whether a reported point can be trusted."""
    for s in branch.special_of("LPC"):
        true = min(abs(s.lam - f) for f in FOLDS)
        assert true / 4 <= s.lam_error <= 10 * true, (s.lam, true, s.lam_error)


@pytest.mark.slow
@pytest.mark.parametrize("N", [32, 56])
def test_kink_fold_error_bar_covers_where_the_halved_mesh_misses(N):
    """With a kink in f the error of a fold depends on where the kink falls between mesh nodes, and it falls
    erratically with N: on these fixed meshes the zero moved on the halved mesh by 0.20 (N = 32) and 0.12 (N = 56)
    of the second fold's true error (1.2e-4, 1.5e-5), and that move was the whole error bar.  The mesh staggered
    by half an interval samples the kink positions anew (measured 7.0e-4 and 3.5e-5): the bar now covers the
    error.  (Over N = 16-64 in steps of 4-8, the halved mesh alone reported less than a quarter of the true error
    for 4 of 22 folds, the larger of the two moves for 1.)"""
    for s in _resonance(N, 0).special_of("LPC"):
        true = min(abs(s.lam - f) for f in FOLDS)
        assert s.lam_error >= true / 2, (N, s.lam, true, s.lam_error)


@pytest.mark.slow
@pytest.mark.parametrize("N", [16, 48])
def test_folds_off_by_more_than_the_mesh_tolerance_are_flagged(N):
    """On coarse uniform meshes the kink puts the second fold 4e-4 to 1e-3 off, and at N = 16 the branch wiggles
    through three folds where there is one.  Before the orbit's mesh error looked at the collocation defects, it
    was below mesh_tol on all of them and nothing was flagged; now every fold that is off by more than mesh_tol
    (1e-4) lies on a flagged point (measured mesh errors 8.4e-4 to 1.4e-3 at N = 16, 1.4e-4 at N = 48), while the
    first fold, off by at most 1.7e-5, passes the mesh test (mesh errors 6.2e-5 and 2.2e-5).  Its multipliers do
    not: the first fold is where the orbit's amplitude reaches the kink (0.50), and at N = 16 the multipliers
    there jump with each collocation point that crosses it (1.0147 and 0.551, then 0.725 +- 0.18i within one
    step, against 0.92 and 0.61, then 0.79 and 0.70 at the same amplitudes on N = 256).  The mode defects flag
    those points (estimates 1.1e-2 to 0.18) since session 11; before, they were reported unflagged."""
    branch = _resonance(N, 0)
    folds = branch.special_of("LPC")
    off = [s for s in folds if min(abs(s.lam - f) for f in FOLDS) > 1e-4]
    assert off  # the case exists on this mesh
    assert all(branch.flagged[s.index] for s in off), [(s.lam, branch.mesh_error[s.index]) for s in off]
    first = min(folds, key=lambda s: abs(s.lam - FOLDS[0]))
    assert abs(first.lam - FOLDS[0]) < 3e-5 and branch.mesh_error[first.index] < branch.mesh_tol


@pytest.mark.parametrize("N, m", [(6, 2), (4, 3)])
def test_period_doubling_error_estimate_on_a_coarse_uniform_mesh(N, m):
    """half_turn_field with the coupling c u (cont_systems): a PD at exactly lam = 0.4, located on a coarse uniform
    mesh 4e-3 (N = 6, m = 2) and 4e-4 (N = 4, m = 3) away from it.  The reported error matches within a factor of
    2 (measured 3.6e-3 and 3.8e-4).  An estimate from the same mesh moved in time had reported 1e-9 and 1e-6: for
    an autonomous problem that is the same discretisation (review of this issue)."""
    from cont_systems import half_turn_field

    st = CycleSettings(m=m, N=N, ds=0.05, ds_max=0.1, max_points=60, lam_min=0.3, lam_max=0.5, adapt=0)
    start = start_from_function(lambda t: np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t), 0 * t, 0 * t], 1),
                                1.0, 0.3, st)
    br = continue_cycles(CycleProblem(half_turn_field, 4, jnp.asarray([2 * np.pi, 0.0, 1.0, 0.3, 0.5, 0.0, 1.0])),
                         st, start)
    pd = br.special_of("PD")
    assert len(pd) == 1 and pd[0].located, br.special
    true = abs(pd[0].lam - 0.4)
    assert true > 1e-4  # a real discretisation error
    assert true / 2 <= pd[0].lam_error <= 2 * true, (true, pd[0].lam_error)


def test_mesh_error_is_infinite_where_f_is_undefined_between_the_nodes():
    """A field that is NaN near the angle 0 of the unit circle (x > 0.999), which the nodes of this orbit miss: its
    defect is NaN, and a NaN mesh error would pass every comparison with mesh_tol (max() would even drop it), so
    the estimate is infinite and the point flagged."""
    def circle(x, lam, args):
        r2 = x[0] ** 2 + x[1] ** 2
        rot = jnp.array([x[0] * (1 - r2) - x[1], x[1] * (1 - r2) + x[0]])
        return jnp.where(x[0] > 0.999, jnp.nan, 1.0) * rot
    sch, mesh = col.Scheme(4), col.uniform_mesh(8)
    shift = 1 / 128  # half a node spacing: no node at the angle 0

    def x_of_t(s):
        return np.stack([np.cos(2 * np.pi * (s + shift)), np.sin(2 * np.pi * (s + shift))], -1)
    o = col.orbit_from_function(x_of_t, 2 * np.pi, 0.0, sch, mesh)
    assert np.all(np.asarray(o.nodes())[..., 0] <= 0.999)
    assert np.isinf(error_estimate(o, sch, circle))
    assert np.isfinite(error_estimate(o, sch))


def test_propagated_errors_agree_between_the_dense_and_sparse_linearisations():
    """The same orbit, its defects carried by the dense condensation's interval sweeps and by the sparse solver's
    SuperLU blocks: two independent factorisations of the same blocks must give the same error."""
    from gfbjax.cont import DenseCondensation, SparseSweep
    from gfbjax.cont._mesh import propagated_errors

    w0 = 1.0
    H = 0.1 / (1 - w0 ** 2 + 0.1j * w0)

    def x_of_t(t):
        e = np.exp(2j * np.pi * t)
        return np.stack([np.real(H * e), np.real(1j * w0 * H * e), e.real, -e.imag], -1)
    st = CycleSettings(m=4, N=16)
    problem = CycleProblem(kinked_oscillator, 4, jac_sparsity=np.ones((4, 4), bool))
    sol, _ = correct_cycle(problem, start_from_function(x_of_t, 2 * np.pi, w0, st).orbit, settings=st)
    o, sch = sol.x, col.Scheme(4)
    out = [propagated_errors(kinked_oscillator, None, o, sch, solver.bind(problem, sch).linearise(o))
           for solver in (DenseCondensation(), SparseSweep())]
    for a, b in zip(*out):
        np.testing.assert_allclose(a, b, rtol=1e-8, atol=1e-12 * np.max(np.abs(a)))
    assert np.max(np.abs(out[0][0])) > 1e-4  # the kink's error, not rounding


def _grazing_contact(x, w, k):
    """A damped oscillator (x, v) forced by a unit-circle oscillator (u, s), with a spring of stiffness k beyond
    x = 0.5 (a contact), the forcing tuned so that the cycle just grazes it."""
    X, v, u, s = x
    r2 = u * u + s * s
    return jnp.array([v, -0.1 * v - X - k * jnp.maximum(X - 0.5, 0.0) + 0.3 * u, u + w * s - u * r2,
                      -w * u + s - s * r2])


def _grazing_monodromy(x0, w, k, T):
    """The exact monodromy matrix: the variational equation integrated with the contact's switching times located
    as events (the Jacobian jumps there), from a point x0 of the cycle."""
    def rhs(t, y, kk):
        X, v, u, s = y[:4]
        r2 = u * u + s * s
        fx = [v, -0.1 * v - X - kk * (X - 0.5) + 0.3 * u, u + w * s - u * r2, -w * u + s - s * r2]
        J = np.array([[0, 1, 0, 0], [-1 - kk, -0.1, 0.3, 0], [0, 0, 1 - 3 * u * u - s * s, w - 2 * u * s],
                      [0, 0, -w - 2 * u * s, 1 - u * u - 3 * s * s]])
        return np.concatenate([fx, (J @ y[4:].reshape(4, 4)).ravel()])

    def switch(t, y, kk):
        return y[0] - 0.5
    switch.terminal = True
    t, y, inside = 0.0, np.concatenate([x0, np.eye(4).ravel()]), x0[0] > 0.5
    while t < T:
        switch.direction = -1.0 if inside else 1.0
        sol = solve_ivp(rhs, (t, T), y, args=(k if inside else 0.0,), events=switch, rtol=1e-12, atol=1e-13,
                        method="DOP853")
        t, y, inside = sol.t[-1], sol.y[:, -1], inside != (sol.status == 1)
    assert np.max(np.abs(y[:4] - x0)) < 1e-6  # x0 lies on the cycle
    return y[4:].reshape(4, 4)


@pytest.fixture(scope="module")
def grazing_cycle():
    """(t, x(t), T, exact multipliers) of the grazing cycle, from a settled time integration."""
    w0, k = 0.8, 1e3
    T = 2 * np.pi / w0
    rhs = jax.jit(_grazing_contact)

    def g(t, x):
        return np.asarray(rhs(jnp.asarray(x), w0, k))
    x1 = solve_ivp(g, (0, 40 * T), [0.0, 0.0, 1.0, 0.0], rtol=1e-10, atol=1e-12, method="Radau").y[:, -1]
    tt = np.linspace(0, T, 4000)
    X = solve_ivp(g, (0, T), x1, t_eval=tt, rtol=1e-10, atol=1e-12, method="Radau").y.T
    return tt, X, T, np.linalg.eigvals(_grazing_monodromy(x1, w0, k, T))


@pytest.mark.parametrize("m, N, collocation", [(2, 256, "radau"), (4, 64, "radau"), (4, 1024, "gauss")])
def test_wrong_multipliers_at_a_grazing_contact_lie_on_flagged_points(grazing_cycle, m, N, collocation):
    """A stiff contact (k = 1e3) that the cycle grazes (0.01 deep): the exact multipliers, from the variational
    equation with the switches located as events, are a complex pair of modulus 0.675 (stable; their product is
    exp(-0.1 T), as Liouville's formula requires).  Collocation gets them badly wrong here, and calls the cycle
    unstable: a real pair 5.9 and 0.073 (Radau m = 2, N = 256), 10.8 and 0.039 (Radau m = 4, N = 64), 1.16 and
    0.39 (Gauss m = 4, N = 1024), while the trivial multiplier is exact to 1e-14.  None of this is reported with
    confidence: the orbit's mesh error is 3.7e-4 to 1.1e-2 there, and the points are flagged.  (Found by a
    fresh-user review of session 10.)"""
    tt, X, T, exact = grazing_cycle
    exact_stable = bool(np.sum(np.abs(exact) > 1 - 1e-6) == 1)  # only the trivial multiplier on the circle
    assert exact_stable
    st = CycleSettings(m=m, N=N, collocation=collocation, max_points=1)
    br = continue_cycles(CycleProblem(_grazing_contact, 4, jnp.asarray(1e3)), st, start_from_samples(tt, X, T, 0.8, st))
    assert bool(br.stable[0]) == exact_stable or bool(br.flagged[0]), (br.multipliers[0], br.mesh_error[0])


def _worst_multiplier_error(mu, exact):
    """The largest distance of a deciding computed multiplier (within 0.6 of the leading modulus) from the exact
    ones, relative to max(1, |mu|)."""
    from gfbjax.cont import nontrivial
    nt = nontrivial(mu)
    return max(np.min(np.abs(z - exact)) / max(1.0, abs(z)) for z in nt[np.abs(nt) > 0.6 * np.max(np.abs(nt))])


@pytest.mark.parametrize("m, N, collocation", [(4, 1536, "radau"), (4, 2048, "radau"), (2, 4096, "gauss")])
def test_wrong_multipliers_of_an_accurate_orbit_at_a_grazing_contact_are_flagged(grazing_cycle, m, N, collocation):
    """The grazing contact on a fine mesh: the orbit passes its mesh test (5e-5 to 7e-5 from the exact cycle),
    but the multipliers do not converge with it.  f is continuous at the contact, so the orbit's error there is
    of order h^2 k; f_x jumps by k, so the variational equation's is of order h k (1.9 at N = 4096), whatever m.
    Measured: a real pair -0.81, -0.56 for the exact complex pair of modulus 0.675 (Radau m = 4, N = 1536), and
    -0.58 +- 0.35i for -0.50 +- 0.46i (N = 4096): errors 0.09 to 0.55.  The running defects of the Floquet modes
    (cont.mode_error) see it: estimates 0.30, 0.014 and 0.17, and the points are flagged.  Before session 11 the
    only multiplier estimate froze f_x at two mesh nodes, missed the contact and flagged none of them."""
    tt, X, T, exact = grazing_cycle
    st = CycleSettings(m=m, N=N, collocation=collocation, max_points=1)
    br = continue_cycles(CycleProblem(_grazing_contact, 4, jnp.asarray(1e3)), st, start_from_samples(tt, X, T, 0.8, st))
    true = _worst_multiplier_error(br.multipliers[0], exact)
    assert br.mesh_error[0] < br.mesh_tol and true > 0.05  # the orbit passes, the multipliers are wrong
    assert br.multiplier_error[0] > br.multiplier_tol and br.flagged[0]
    assert br.multiplier_error[0] > true / 8, (br.multiplier_error[0], true)


@pytest.mark.parametrize("collocation", ["gauss", "radau"])
def test_mode_error_of_a_smooth_cycle_is_the_multipliers_error(collocation):
    """Van der Pol (mu = 0.5) on 8 intervals: the non-trivial multiplier (0.039) against the same cycle on 512
    intervals is off by 2.3e-6 (Gauss) and 4.3e-5 (Radau); the mode defects estimate 5.1e-6 and 2.4e-5."""
    from gfbjax.cont import mode_error
    from gfbjax.cont._cycles import analyse

    tt, X, T = _van_der_pol_cycle(0.5)
    problem = CycleProblem(van_der_pol, 2)
    out = {}
    for N in (512, 8):
        st = CycleSettings(m=4, N=N, collocation=collocation)
        sol, lin = correct_cycle(problem, start_from_samples(tt, X, T, 0.5, st).orbit, settings=st)
        mu = analyse(problem, lin)["spectrum"]
        out[N] = (mu[np.argmax(np.abs(mu - 1))], mode_error(van_der_pol, None, sol.x, col.Scheme(4, collocation),
                                                            lin, mu))
    true = abs(out[8][0] - out[512][0])
    assert true > 1e-6 and out[512][1] < true / 100  # a measurable error, and a reference far more accurate
    assert true / 3 <= out[8][1] <= 3 * true, (true, out[8][1])


def test_mode_error_agrees_between_the_dense_and_sparse_linearisations(grazing_cycle):
    """The grazing contact with a damped chain of 30 states downstream (no action back): the block Krylov Ritz
    pairs of the sparse solver and the eigenvectors of the dense monodromy must give the same estimate."""
    from gfbjax.cont import DenseCondensation, SparseSweep, mode_error
    from gfbjax.cont._cycles import analyse

    def chained(x, w, k):
        tail = x[4:]
        return jnp.concatenate([_grazing_contact(x[:4], w, k),
                                -2.0 * tail + 0.1 * jnp.concatenate([x[:1], tail[:-1]])])

    n = 34
    pattern = np.zeros((n, n), bool)
    pattern[:4, :4] = True
    pattern[np.arange(4, n), np.arange(4, n)] = True
    pattern[np.arange(4, n), np.arange(3, n - 1)] = True
    pattern[4, 3] = False
    pattern[4, 0] = True
    tt, X, T, exact = grazing_cycle
    Xc = np.concatenate([X, np.zeros((len(tt), n - 4))], axis=1)
    st = CycleSettings(m=4, N=128, collocation="radau")
    problem = CycleProblem(chained, n, jnp.asarray(1e3), jac_sparsity=pattern)
    sol, _ = correct_cycle(problem, start_from_samples(tt, Xc, T, 0.8, st).orbit, settings=st)
    o, sch = sol.x, col.Scheme(4, "radau")
    est = []
    for solver in (DenseCondensation(), SparseSweep()):
        lin = solver.bind(problem, sch).linearise(o)
        an = analyse(problem, lin)
        assert (an["modes"] is None) == (solver.name == "dense")  # the sparse estimate uses the Krylov Ritz pairs
        est.append(mode_error(chained, jnp.asarray(1e3), o, sch, lin, an["spectrum"], an["modes"]))
    assert est[0] > 1e-3 and est[1] == pytest.approx(est[0], rel=1e-6)
