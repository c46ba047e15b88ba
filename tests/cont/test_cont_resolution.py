"""Modes of the linearisation that the mesh does not resolve, while the orbit, its mesh estimate and the trivial
multiplier are all accurate.  Fast modes: Gauss collocation gives them spurious Floquet multipliers near the unit
circle (its stability function tends to (-1)^m); Radau points (L-stable) give them their true, tiny multipliers.
Modes oscillating within a mesh interval: both get wrong multipliers (Radau damps them away).  The branch estimates
both (Branch.stiff_modulus, Branch.multiplier_error) and flags the points.

Reference values are closed forms: the Pade approximants of exp (Gauss: diagonal (m, m); Radau IIA: (m - 1, m)),
and the multipliers of a Stuart-Landau cycle driving a linear mode that does not act back (the monodromy is block
triangular): {1, exp(-2 lam T)} and that mode's exp(mu T)."""
import math

import jax.numpy as jnp
import numpy as np
import pytest

from gfbjax.cont import Branch, CycleProblem, CycleSettings, Scheme, continue_cycles, nontrivial, start_from_function

W, LAM = 2.0, 0.5
T = 2 * np.pi / W


def _pade(z, k, j):
    """The (k, j) Pade approximant of exp(z) (numerator degree k, denominator degree j), in closed form."""
    def poly(deg, other, sign):
        return sum(math.factorial(k + j - i) * math.factorial(deg) / (math.factorial(k + j) * math.factorial(i)
                                                                       * math.factorial(deg - i)) * (sign * z) ** i
                   for i in range(deg + 1))
    return poly(k, j, 1.0) / poly(j, k, -1.0)


@pytest.mark.parametrize("m", [2, 3, 4, 5])
def test_stability_functions_are_the_pade_approximants(m):
    z = np.array([-0.3, -2.0, -40.0, -1e4, -3.0 + 2.0j, 0.7j])
    assert np.allclose(Scheme(m, "gauss").stability(z), [_pade(v, m, m) for v in z], rtol=1e-12, atol=1e-14)
    assert np.allclose(Scheme(m, "radau").stability(z), [_pade(v, m - 1, m) for v in z], rtol=1e-12, atol=1e-14)
    # the limits that decide the fast modes' multipliers
    assert abs(Scheme(m, "gauss").stability(-1e9) - (-1) ** m) < 1e-6
    assert abs(Scheme(m, "radau").stability(-1e9)) < 1e-6


def _driven(x, lam, K):
    """Stuart-Landau cycle (radius sqrt(lam)) driving z' = K (x0^2 - z); z does not act back, so the monodromy is
    block triangular and the multipliers are 1, exp(-2 lam T) and exp(-K T)."""
    r2 = x[0] ** 2 + x[1] ** 2
    return jnp.array([lam * x[0] - W * x[1] - x[0] * r2, W * x[0] + lam * x[1] - x[1] * r2, K * (x[0] ** 2 - x[2])])


def _branch(K, collocation, N=20, m=4):
    st = CycleSettings(m=m, N=N, max_points=1, adapt=0, collocation=collocation)
    a = math.sqrt(LAM)
    start = start_from_function(lambda t: np.stack([a * np.cos(2 * np.pi * t), a * np.sin(2 * np.pi * t),
                                                    LAM * np.cos(2 * np.pi * t) ** 2], 1), T, LAM, st)
    return continue_cycles(CycleProblem(_driven, 3, jnp.asarray(K)), st, start)


def test_gauss_gives_an_unresolved_fast_mode_a_spurious_multiplier_and_the_point_is_flagged():
    """K = 1e5 with N = 20: h K = 1.6e4.  The fast mode's exact multiplier exp(-K T) underflows to 0; Gauss
    collocation gives it R(-h K)^N = 0.950, inside the circle (stability is right) but in the band where the trivial
    multiplier and events are decided.  Nothing else shows it: the trivial multiplier and the mesh estimate are
    fine."""
    K, N = 1e5, 20
    br = _branch(K, "gauss", N)
    mu = np.sort(np.abs(br.multipliers[0]))[::-1]
    spurious = abs(_pade(-K * T / N, 4, 4)) ** N
    assert spurious > 0.95
    assert abs(mu[1] - spurious) < 1e-8 and abs(mu[2] - math.exp(-2 * LAM * T)) < 1e-7
    assert br.trivial_error[0] < 1e-10 and br.mesh_error[0] < 1e-5 and br.stable[0]
    # the estimate: the fast mode's rate is K everywhere, so the frozen-coefficient model reproduces it
    assert abs(br.stiff_modulus[0] - spurious) < 1e-9
    assert br.stiff_tol == 0.9 and br.flagged[0]


def test_radau_gives_the_fast_mode_its_true_multiplier():
    br = _branch(1e5, "radau")
    mu = np.sort(np.abs(br.multipliers[0]))[::-1]
    assert abs(mu[0] - 1.0) < 1e-10 and abs(mu[1] - math.exp(-2 * LAM * T)) < 1e-6 and mu[2] < 1e-8
    assert br.stiff_modulus[0] < 1e-8 and not br.flagged[0] and br.collocation == "radau"


def test_a_resolved_fast_mode_is_not_flagged():
    """K = 10: h K = 1.6, resolved; the multiplier exp(-K T) = 2e-14 comes out as such."""
    br = _branch(10.0, "gauss")
    assert br.stiff_modulus[0] < 1e-8 and not br.flagged[0]
    assert np.sort(np.abs(br.multipliers[0]))[0] < 1e-10


def test_the_estimate_and_the_scheme_travel_with_the_branch(tmp_path):
    br = _branch(1e5, "gauss")
    br.save(tmp_path / "b")
    back = Branch.load(tmp_path / "b")
    assert back.collocation == "gauss" and back.stiff_tol == 0.9
    assert np.array_equal(back.stiff_modulus, br.stiff_modulus) and back.flagged[0]
    ds = br.to_xarray()
    assert float(ds["stiff_modulus"][0]) == pytest.approx(float(br.stiff_modulus[0]))


def test_collocation_settings_are_checked():
    with pytest.raises(ValueError, match="collocation"):
        CycleSettings(collocation="lobatto")
    with pytest.raises(ValueError, match="stiff_tol"):
        CycleSettings(stiff_tol=0.0)
    with pytest.raises(ValueError, match="collocation"):
        Scheme(4, "Gauss")


def _oscillator(x, lam, a):
    """Stuart-Landau cycle driving a damped oscillator x2'' + 2 zeta w x2' + w^2 x2 = x0^2 (no action back): its
    multipliers are exp(mu T), mu = w (-zeta +- i sqrt(1 - zeta^2))."""
    r2 = x[0] ** 2 + x[1] ** 2
    w, zeta = a[0], a[1]
    return jnp.array([lam * x[0] - W * x[1] - x[0] * r2, W * x[0] + lam * x[1] - x[1] * r2, x[3],
                      -w ** 2 * x[2] - 2 * zeta * w * x[3] + x[0] ** 2])


@pytest.mark.parametrize("collocation", ["gauss", "radau"])
def test_a_mode_oscillating_within_an_interval_gets_a_wrong_multiplier_and_the_point_is_flagged(collocation):
    """w = 20 (about 6 oscillations per period), zeta = 0.02: exact pair modulus exp(-zeta w T) = 0.2846.  With
    N = 10 intervals Gauss points give 0.3485, Radau points damp the pair below the 0.0432 of the cycle's own
    mode; with N = 40 both are right to 3e-4.  The estimate (exact here: the Jacobian of the driven oscillator is
    constant) is the error of the complex multiplier, so it bounds the modulus' error, and it decides the flag."""
    w, zeta = 20.0, 0.02
    mu_exact = np.exp(w * (-zeta + 1j * math.sqrt(1 - zeta ** 2)) * T)
    for N, flagged in ((10, True), (40, False)):
        st = CycleSettings(m=4, N=N, max_points=1, adapt=0, collocation=collocation)
        a = math.sqrt(LAM)
        start = start_from_function(lambda t: np.stack([a * np.cos(2 * np.pi * t), a * np.sin(2 * np.pi * t),
                                                        0 * t + LAM / 2 / w ** 2, 0 * t], 1), T, LAM, st)
        br = continue_cycles(CycleProblem(_oscillator, 4, jnp.asarray([w, zeta])), st, start)
        mu = np.asarray(br.multipliers[0])
        near = mu[np.argmin(np.abs(np.abs(mu) - abs(mu_exact)))]  # the computed member nearest the exact modulus
        h = T / N
        z = h * w * (-zeta + 1j * math.sqrt(1 - zeta ** 2))
        predicted = _pade(z, 4 if collocation == "gauss" else 3, 4) ** N  # the closed form, not Scheme.stability
        assert br.multiplier_error[0] == pytest.approx(abs(predicted - mu_exact), rel=1e-6)
        assert br.multiplier_error[0] >= abs(abs(near) - abs(mu_exact)) - 1e-9
        assert bool(br.flagged[0]) is flagged and br.trivial_error[0] < 1e-9 and br.mesh_error[0] < 1e-4
        if N == 40:
            assert abs(abs(near) - abs(mu_exact)) < 3e-4
    if collocation == "gauss":
        assert br.stiff_modulus[0] < 1e-6


def test_a_leading_spurious_multiplier_is_flagged_whatever_its_size():
    """Review case: a driven mode mu = -2.3 + 200i has the exact multiplier |exp(mu T)| = 7.3e-4, yet N = 20
    Gauss intervals give it 0.743, the largest non-trivial multiplier (the cycle's own is 0.043).  That is below
    stiff_tol, so only the error of the multipliers that decide the leading modulus can flag it."""
    mu = -2.3 + 200.0j

    def driven(x, lam, a):
        r2 = x[0] ** 2 + x[1] ** 2
        return jnp.array([lam * x[0] - W * x[1] - x[0] * r2, W * x[0] + lam * x[1] - x[1] * r2,
                          mu.real * x[2] - mu.imag * x[3] + x[0] ** 2, mu.imag * x[2] + mu.real * x[3]])

    st = CycleSettings(m=4, N=20, max_points=1, adapt=0)
    a = math.sqrt(LAM)
    start = start_from_function(lambda t: np.stack([a * np.cos(2 * np.pi * t), a * np.sin(2 * np.pi * t),
                                                    0 * t, 0 * t], 1), T, LAM, st)
    br = continue_cycles(CycleProblem(driven, 4, None), st, start)
    leading = np.sort(np.abs(br.multipliers[0]))[::-1][1]
    assert abs(leading - abs(_pade(mu * T / 20, 4, 4)) ** 20) < 1e-6 and leading > 0.7
    assert abs(np.exp(mu * T)) < 1e-3 and br.stiff_modulus[0] < br.stiff_tol
    assert br.multiplier_error[0] > 0.7 and br.flagged[0]


@pytest.mark.parametrize("collocation", ["gauss", "radau"])
def test_the_halved_estimate_of_a_constant_mode_is_the_closed_form_change(collocation):
    """A driven mode mu = -0.1 + 10i (exact multiplier modulus 0.73, the leading non-trivial one) on N = 8
    intervals, h |mu| = 3.9: the collocation multiplier is R(h mu)^N and on the halved mesh R(h mu / 2)^(2N), with R
    the scheme's Pade approximant of exp (closed form, not Scheme.stability).  halved_error is their distance."""
    from gfbjax.cont import CycleProblem as CP, Scheme, analyse, bind_solver, correct_cycle, halved_error

    mu, N = -0.1 + 10.0j, 8

    def driven(x, lam, a):
        r2 = x[0] ** 2 + x[1] ** 2
        return jnp.array([lam * x[0] - W * x[1] - x[0] * r2, W * x[0] + lam * x[1] - x[1] * r2,
                          mu.real * x[2] - mu.imag * x[3] + x[0] ** 2, mu.imag * x[2] + mu.real * x[3]])

    st = CycleSettings(m=4, N=N, max_points=1, adapt=0, collocation=collocation)
    a = math.sqrt(LAM)
    start = start_from_function(lambda t: np.stack([a * np.cos(2 * np.pi * t), a * np.sin(2 * np.pi * t),
                                                    0 * t, 0 * t], 1), T, LAM, st)
    problem, scheme = CP(driven, 4, None), Scheme(4, collocation)
    sol, lin = correct_cycle(problem, start.orbit, settings=st)
    assert sol.converged
    an = analyse(problem, lin)
    k = 4 if collocation == "gauss" else 3
    coarse, fine = _pade(mu * T / N, k, 4) ** N, _pade(mu * T / (2 * N), k, 4) ** (2 * N)
    assert abs(coarse) > 0.5 and abs(coarse - np.exp(mu * T)) > 1e-3  # deciding, and visibly off
    expected = min(abs(coarse - fine), abs(coarse - np.conj(fine))) / max(1.0, abs(coarse))
    got = halved_error(sol.x, scheme, lin, an["spectrum"], bind_solver(problem, scheme, st).linearise, an["modes"])
    assert got == pytest.approx(expected, rel=1e-6)


def test_the_estimates_do_not_depend_on_the_time_origin():
    """Review case: the Jacobian was frozen at the first mesh node only, so the same cycle started half a period
    later got another estimate and another flag.  A mode z' = -(0.5 + 20 x0 / a) z swings between rates -20.5 and
    19.5 along the orbit."""
    def swing(x, lam, a):
        r2 = x[0] ** 2 + x[1] ** 2
        return jnp.array([lam * x[0] - W * x[1] - x[0] * r2, W * x[0] + lam * x[1] - x[1] * r2,
                          -(0.5 + 20.0 * x[0] / math.sqrt(LAM)) * x[2]])

    st = CycleSettings(m=4, N=20, max_points=1, adapt=0)
    a = math.sqrt(LAM)
    out = []
    for phase in (0.0, np.pi):
        start = start_from_function(lambda t: np.stack([a * np.cos(2 * np.pi * t + phase),
                                                        a * np.sin(2 * np.pi * t + phase), 0 * t], 1), T, LAM, st)
        br = continue_cycles(CycleProblem(swing, 3, None), st, start)
        out.append((br.stiff_modulus[0], br.multiplier_error[0], bool(br.flagged[0])))
    assert out[0] == pytest.approx(out[1], rel=1e-6)


def test_a_start_mesh_that_is_no_mesh_is_refused():
    """Review case: meshes out of order, of one interval or not from 0 to 1 were taken as given, and the branch
    converged to a wrong period without a word."""
    st = CycleSettings(m=3, N=10, max_points=3, adapt=0)
    a = math.sqrt(LAM)

    def circle(t):
        return np.stack([a * np.cos(2 * np.pi * t), a * np.sin(2 * np.pi * t), 0 * t], 1)

    for mesh in ([0, 0.5, 0.3, 1], [0, 1], np.linspace(0.2, 1, 11), [0, 0.5, 0.5, 1], [0, np.nan, 1]):
        with pytest.raises(ValueError, match="mesh must increase strictly from 0 to 1"):
            start_from_function(circle, T, LAM, st, mesh=mesh)
    with pytest.raises(ValueError, match="lam must be a number"):
        start_from_function(circle, T, True, st)
    with pytest.raises(ValueError, match="T \\(period\\) must be a number"):
        start_from_function(circle, -1.0, LAM, st)
    good = start_from_function(circle, T, LAM, st)
    o = good.orbit
    bent = type(good)(type(o)(jnp.asarray([0.0, 0.5, 0.3] + list(np.linspace(0.4, 1, 8))), o.xm, o.xi, o.T, o.lam))
    with pytest.raises(ValueError, match="start orbit's mesh must increase"):
        continue_cycles(CycleProblem(_driven, 3, jnp.asarray(10.0)), st, bent)


def _stiff_stretch(x, w, args):
    """A unit-circle oscillator driving nothing, beside a weakly damped mode (q, p) on the invariant set q = 0 whose
    stiffness rises 100x, smoothly, over about a quarter of the period (review case of session 11)."""
    zeta, om = args
    u, s, q, p = x
    r2 = u * u + s * s
    stiff = 1.0 + 99.0 * 0.5 * (1.0 + jnp.tanh(10.0 * (-s - 0.7)))
    return jnp.array([u + 0.8 * s - u * r2, -0.8 * u + s - s * r2, p, -om ** 2 * stiff * q - zeta * p])


@pytest.mark.parametrize("collocation, N", [("radau", 40), ("radau", 80), ("gauss", 20), ("gauss", 40)])
def test_a_mode_stiff_on_part_of_the_period_is_labelled_right_or_flagged(collocation, N):
    """The orbit (u, s) = (cos 0.8t, -sin 0.8t), q = 0 is exact on any mesh.  The (q, p) mode's exact multipliers
    (its 2x2 variational equation integrated by DOP853) are -0.1673 +- 1.0060i, of modulus 1.0198: unstable.
    Radau points, m = 4, N = 40, gave a pair of modulus 0.83 (stable), 0.244 from the exact one, while the mesh
    error was 2e-9 and the frozen and mode-defect estimates 1.2e-4 (review case of session 11): the frozen model
    looks at two mesh nodes, both where the mode is soft, and the mode defects vanish where f_x is constant over
    an interval (module docstring of _resolution).  Radau N = 80 and Gauss N = 20 and 40 label the pair unstable,
    but its errors (2.9e-3, 0.25, 0.077: mostly in the angle, the mode turns about 40 rad on the stiff stretch)
    were estimated at 4.5e-7, 6.4e-4 and 2.9e-5.  The halved intervals see all four: that estimate is within 2x
    of the true error, so the point is flagged (multiplier_tol 1e-3)."""
    from scipy.integrate import solve_ivp

    from gfbjax.cont import analyse, bind_solver, correct_cycle, halved_error

    zeta, om, w = -0.005, 2.05, 0.8
    T = 2 * np.pi / w

    def variational(t, y):
        k = om ** 2 * (1 + 99.0 * 0.5 * (1 + np.tanh(10.0 * (np.sin(w * t) - 0.7))))
        return (np.array([[0.0, 1.0], [-k, -zeta]]) @ y.reshape(2, 2)).ravel()
    Phi = solve_ivp(variational, (0, T), np.eye(2).ravel(), rtol=1e-12, atol=1e-13, method="DOP853",
                    max_step=0.01).y[:, -1].reshape(2, 2)
    exact = np.linalg.eigvals(Phi)
    exact_stable = bool(np.all(np.abs(exact) < 1.0))
    assert not exact_stable
    st = CycleSettings(m=4, N=N, collocation=collocation, max_points=1)
    start = start_from_function(lambda t: np.stack([np.cos(2 * np.pi * t), -np.sin(2 * np.pi * t), 0 * t, 0 * t], 1),
                                T, w, st)
    problem = CycleProblem(_stiff_stretch, 4, (jnp.asarray(zeta), jnp.asarray(om)))
    br = continue_cycles(problem, st, start)
    mu = br.multipliers[0]
    pair = nontrivial(mu, 1)[:2]  # the (q, p) pair; the other non-trivial multiplier is 1.5e-7
    true = float(np.max(np.min(np.abs(pair[:, None] - exact[None, :]), axis=1)) / max(1.0, np.max(np.abs(pair))))
    assert true > br.multiplier_tol
    sol, lin = correct_cycle(problem, start.orbit, settings=st)
    an = analyse(problem, lin)
    scheme = Scheme(4, collocation)
    halved = halved_error(sol.x, scheme, lin, an["spectrum"], bind_solver(problem, scheme, st).linearise)
    assert true / 2 < halved < 2 * true, (mu, true, halved)
    # the recorded estimate is the largest of three (the frozen model overestimates here: it applies the stiff
    # stretch's eigenvalues to the whole period)
    assert br.multiplier_error[0] >= halved and bool(br.flagged[0])


def _exact_block(k_of_s, zeta, w=0.8):
    """Multipliers of q'' + zeta q' + k(s(t)) q = 0 along s = -sin(w t) over one period (DOP853 on the 2x2
    variational equation): the closed orbit's (q, p) block, whatever the mesh."""
    from scipy.integrate import solve_ivp

    def rhs(t, y):
        return (np.array([[0.0, 1.0], [-k_of_s(-np.sin(w * t)), -zeta]]) @ y.reshape(2, 2)).ravel()
    P = solve_ivp(rhs, (0, 2 * np.pi / w), np.eye(2).ravel(), rtol=1e-12, atol=1e-14, method="DOP853",
                  max_step=0.002).y[:, -1]
    return np.linalg.eigvals(P.reshape(2, 2))


def _unit_circle(st, extra):
    return start_from_function(lambda t: np.stack([np.cos(2 * np.pi * t), -np.sin(2 * np.pi * t)]
                                                  + [0 * t] * extra, 1), 2 * np.pi / 0.8, 0.8, st)


@pytest.mark.parametrize("sparse", [False, True])
def test_a_mode_the_coarse_mesh_damps_below_the_deciding_floor_is_flagged(sparse):
    """Review case of session 12: the stiff-stretch oscillator beside a decoupled mode v' = -a v of multiplier 0.5.
    Radau, m = 4, N = 20 damps the (q, p) pair (exact modulus 1.0198, unstable) to 0.21, below 0.9 x 0.5, so the
    modes chosen on the N mesh left it out, and every estimate was below 1e-5: 'stable', unflagged, with either
    solver.  The pair is 0.83 on the halved mesh, and the frozen model sees it where the Jacobian is frozen on the
    stiff stretch: flagged."""
    from gfbjax.cont import SparseSweep

    zeta, om, w = -0.005, 2.05, 0.8
    a_v = -math.log(0.5) / (2 * np.pi / w)

    def k_of_s(s, xp=np):
        return om ** 2 * (1.0 + 99.0 * 0.5 * (1.0 + xp.tanh(10.0 * (-s - 0.7))))

    def f(x, lam, args):
        u, s, q, p, v = x
        r2 = u * u + s * s
        return jnp.array([u + lam * s - u * r2, -lam * u + s - s * r2, p, -k_of_s(s, jnp) * q - zeta * p, -a_v * v])

    exact = _exact_block(k_of_s, zeta)
    assert np.all(np.abs(exact) > 1.0)  # unstable
    pattern = np.array([[1, 1, 0, 0, 0], [1, 1, 0, 0, 0], [1, 1, 1, 1, 0], [1, 1, 1, 1, 0], [0, 0, 0, 0, 1]], bool)
    st = CycleSettings(m=4, N=20, max_points=1, adapt=0, collocation="radau",
                       linear_solver=SparseSweep() if sparse else None)
    br = continue_cycles(CycleProblem(f, 5, None, jac_sparsity=pattern if sparse else None), st, _unit_circle(st, 3))
    mu = nontrivial(br.multipliers[0], 1)
    assert np.max(np.abs(mu)) < 0.51 and bool(br.stable[0])  # the wrong label this is about
    assert br.multiplier_error[0] > 0.5 and bool(br.flagged[0])


def test_a_mode_unresolved_on_both_meshes_is_flagged():
    """Review case of session 12: q'' + 0.005 q' + 1.6^2 k q = 0 with k rising 2500x (frequency 50x) on a stretch of
    the period.  Its exact multipliers are real, 2.76 and 0.35 (unstable).  Radau, m = 4, damps the pair to 1.7e-6 on
    N = 40 and 2.9e-4 on the halved mesh, so the change on halving is 3e-4; with the Jacobian frozen at two nodes, both
    off the stretch, every estimate was below 1e-8: 'stable', unflagged.  Frozen at every mesh node (5 states: well
    within FROZEN_BUDGET) the model sees the undamped fast oscillation there: flagged."""
    zeta, om = 0.005, 1.6

    def k_of_s(s, xp=np):
        return om ** 2 * (1.0 + (50.0 ** 2 - 1.0) * 0.5 * (1.0 + xp.tanh(10.0 * (-s - 0.7))))

    def f(x, lam, args):
        u, s, q, p = x
        r2 = u * u + s * s
        return jnp.array([u + lam * s - u * r2, -lam * u + s - s * r2, p, -k_of_s(s, jnp) * q - zeta * p])

    exact = _exact_block(k_of_s, zeta)
    assert np.max(np.abs(exact)) > 2.0  # unstable
    st = CycleSettings(m=4, N=40, max_points=1, adapt=0, collocation="radau")
    br = continue_cycles(CycleProblem(f, 4, None), st, _unit_circle(st, 2))
    assert bool(br.stable[0]) and np.max(np.abs(nontrivial(br.multipliers[0], 1))) < 1e-3
    assert br.multiplier_error[0] > 0.5 and bool(br.flagged[0])


def test_gauss_on_a_stiff_stretch_that_starts_and_ends_on_mesh_nodes_is_flagged():
    """Review case of session 12: z' = -K z with K = 1e8 on tau in [0.1, 0.4] exactly (mesh nodes of N = 20) and
    K = -0.05 elsewhere.  Exact multiplier exp(0.05 0.7 T - 1e8 0.3 T) = 0 (stable); Gauss, m = 4, gives the
    stretch R(-h K)^6 = 1 and the cycle 1.32 (unstable), on the halved mesh too, and the modes' defects vanish.
    With two frozen nodes, both off the stretch, nothing was flagged; frozen at every node, the fast mode's
    spurious multiplier is seen (stiff_modulus 1 > stiff_tol) and the point is flagged."""
    c0 = math.sin(0.2 * math.pi)

    def f(x, lam, args):
        u, s, z = x
        r2 = u * u + s * s
        return jnp.array([u + lam * s - u * r2, -lam * u + s - s * r2, -jnp.where(-s > c0, 1e8, -0.05) * z])

    st = CycleSettings(m=4, N=20, max_points=1, adapt=0, collocation="gauss")
    br = continue_cycles(CycleProblem(f, 3, None), st, _unit_circle(st, 1))
    assert not bool(br.stable[0])  # wrong: the exact multipliers are exp(-2T) and 0
    assert br.stiff_modulus[0] > br.stiff_tol and bool(br.flagged[0])
