"""Every reported bifurcation real, every real one reported: continuous test functions of cycles, collisions on the
real axis, neutral saddles, discontinuous test functions, and the parameter bound.  Known answers in closed form
(cont_systems.half_turn_field)."""
import jax.numpy as jnp
import numpy as np
import pytest

from gfbjax.cont import (CycleProblem, CycleSettings, EquilibriumProblem, EquilibriumSettings, Outcome,
                         continue_cycles, continue_equilibria, locate, start_from_function)
from cont_systems import half_turn_field, half_turn_multipliers

W = 2 * np.pi  # T = 1


def _cycle_start(lam, st):
    return start_from_function(lambda t: np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t), 0 * t, 0 * t], 1),
                               2 * np.pi / W, lam, st)


def _branch(p, lam0, lam1, **kw):
    st = CycleSettings(m=4, N=12, ds=0.05, ds_max=0.1, max_points=60, lam_min=min(lam0, lam1),
                       lam_max=max(lam0, lam1), direction=1 if lam1 > lam0 else -1, **kw)
    return continue_cycles(CycleProblem(half_turn_field, 4, jnp.asarray(p)), st, _cycle_start(lam0, st))


def test_real_axis_collision_outside_the_circle_is_no_bifurcation():
    """mu from 0.6 down to 0: the multipliers -exp((0.8 +- sqrt(mu^2 - 0.09)))  (two reals below -1) merge at
    mu = 0.3 into a complex pair of modulus exp(0.8) = 2.23; nothing crosses the unit circle."""
    p = [W, 0.8, 0.0, 0.3, 0.0, 1.0]  # lam = mu
    br = _branch(p, 0.6, 0.0)
    assert br.outcome is Outcome.REACHED_END, br.message
    assert br.special == [], br.special
    assert br.lam.min() < 0.3 < br.lam.max()  # the collision was passed
    for lam, mu in zip(br.lam, br.multipliers):
        ref = half_turn_multipliers(p, lam)
        nt = np.asarray(mu)[np.argsort(np.abs(np.asarray(mu) - 1.0))[1:]]  # the trivial multiplier removed
        np.testing.assert_allclose(np.sort_complex(nt), np.sort_complex(ref), rtol=1e-6, atol=1e-9)


def test_neutral_saddle_is_no_neimark_sacker():
    """gamma from -0.1 to 0.1 with mu = 0.5 > delta: the real multipliers -exp(gamma +- 0.4) have product exp(2
    gamma), which passes 1 at gamma = 0 (the NS test function vanishes there), but neither crosses the circle."""
    p = [W, 0.0, 1.0, 0.3, 0.5, 0.0]  # lam = gamma
    br = _branch(p, -0.1, 0.1)
    assert br.outcome is Outcome.REACHED_END, br.message
    assert br.special == [], br.special


def test_neimark_sacker_is_located_with_its_angle():
    """gamma from -0.1 to 0.1 with mu = 0.1 < delta: the complex pair -exp(gamma) exp(+-i sqrt(0.08)) crosses the
    unit circle at gamma = 0 with angle pi - sqrt(0.08)."""
    p = [W, 0.0, 1.0, 0.3, 0.1, 0.0]
    br = _branch(p, -0.1, 0.1)
    ns = br.special_of("NS")
    assert len(ns) == 1 and ns[0].located, br.special
    assert abs(ns[0].lam) < 1e-8 and abs(ns[0].residual) < 1e-8
    assert abs(ns[0].angle - (np.pi - np.sqrt(0.08))) < 1e-7
    assert [s.type for s in br.special] == ["NS"]
    assert br.stable[0] and not br.stable[-1]


def test_period_doubling_while_a_torus_pair_is_already_outside():
    """A PD while another multiplier is already unstable is still reported: mu = 0.5, gamma from 0.3 to 0.5 moves
    -exp(gamma - 0.4) through -1 at gamma = 0.4 while -exp(gamma + 0.4) stays below -1."""
    p = [W, 0.0, 1.0, 0.3, 0.5, 0.0]
    br = _branch(p, 0.3, 0.5)
    pd = br.special_of("PD")
    assert len(pd) == 1 and pd[0].located, br.special
    assert abs(pd[0].lam - 0.4) < 1e-8
    assert not br.stable[0]  # the other multiplier was already outside


def test_last_point_is_on_the_bound():
    """x' = p - x, lam_max = 1, ds = 0.3: no point and no event beyond the bound, the last point exactly on it."""
    prob = EquilibriumProblem(lambda x, lam, a: lam - x, 1)
    br = continue_equilibria(prob, EquilibriumSettings(ds=0.3, ds_max=0.3, lam_max=1.0), [0.0], 0.0)
    assert br.outcome is Outcome.REACHED_END, br.message
    assert br.lam[-1] == pytest.approx(1.0, abs=1e-12) and np.all(br.lam <= 1.0 + 1e-12)
    np.testing.assert_allclose(br.states["x"][:, 0], br.lam, atol=1e-12)


def test_a_jump_is_bracketed_not_located():
    """A test function that changes sign by a jump (as the critical eigenvalue of a coarse model can) is reported
    as bracketed, with its value at the returned point, never as located."""
    s, _, val, located = locate(lambda s: (-0.5 if s < 0.3 else 0.7, None), 1.0, -0.5, 0.7, tol=1e-10)
    assert not located and abs(val) >= 0.5 and abs(s - 0.3) < 1e-8
    s, _, val, located = locate(lambda s: (s - 0.3, None), 1.0, -0.3, 0.7, tol=1e-10)
    assert located and abs(s - 0.3) < 1e-10


def test_every_hopf_point_is_reported():
    """Two Hopf pairs, (lam - 1) +- i and (lam - 2) +- 1.7 i: both crossings, the second while the first pair is
    already unstable, each located with its frequency."""
    from cont_systems import two_hopf_pairs
    br = continue_equilibria(EquilibriumProblem(two_hopf_pairs, 4), EquilibriumSettings(ds=0.1, ds_max=0.2,
                             lam_max=3.0), np.zeros(4), 0.0)
    hs = br.special_of("HOPF")
    assert [round(h.lam, 9) for h in hs] == [1.0, 2.0], br.special
    assert all(h.located for h in hs)
    np.testing.assert_allclose([h.omega for h in hs], [1.0, 1.7], rtol=1e-9)


def test_neutral_saddle_is_no_hopf():
    """Eigenvalues lam +- 1 (and -1): at lam = 0 a real pair sums to zero, the Hopf test function vanishes, but
    there is no Hopf bifurcation."""
    from cont_systems import saddle_family
    br = continue_equilibria(EquilibriumProblem(saddle_family, 3), EquilibriumSettings(ds=0.1, lam_min=-0.5,
                             lam_max=0.5), np.zeros(3), -0.5)
    assert br.outcome is Outcome.REACHED_END and br.special_of("HOPF") == [], br.special


def test_inaccurate_points_are_flagged():
    """Van der Pol at mu = 3 (a relaxation oscillation): on a coarse mesh the trivial multiplier is far from +1,
    and such points are flagged (their stability labels cannot be trusted); on a fine mesh they are not."""
    from scipy.integrate import solve_ivp
    from gfbjax.cont import Branch, start_from_samples
    from cont_systems import van_der_pol

    mu = 3.0
    rhs = lambda t, y: [y[1], mu * (1 - y[0] ** 2) * y[1] - y[0]]  # noqa: E731
    ev = lambda t, y: y[1]  # noqa: E731
    ev.direction = -1
    s = solve_ivp(rhs, (0, 60), [2.0, 0.0], rtol=1e-10, atol=1e-10, events=ev, dense_output=True)
    te = s.t_events[0]
    t = np.linspace(te[-2], te[-1], 400)
    out = {}
    for N, m in ((6, 2), (60, 5)):
        st = CycleSettings(m=m, N=N, ds=0.05, max_points=2, trivial_tol=1e-5)
        out[N] = continue_cycles(CycleProblem(van_der_pol, 2, jnp.asarray(mu)), st,
                                 start_from_samples(t, s.sol(t).T, te[-1] - te[-2], 0.0, st))
    assert np.all(out[6].trivial_error > 1e-2) and np.all(out[6].flagged)
    assert np.all(out[60].trivial_error < 1e-6) and not np.any(out[60].flagged)
    back = Branch.from_points("cycles", [0], [], [], [], Outcome.MAX_POINTS, accuracy_tol=1e-5)
    assert back.flagged.shape == (0,)
    with pytest.raises(ValueError, match="trivial_tol"):
        CycleSettings(trivial_tol=0.0)


def test_start_exactly_at_a_fold_gives_both_halves():
    """x' = p - x^2 from its fold (0, 0): fixing p is singular there; the start goes along the null tangent and
    the two directions give the two halves x = +sqrt(p) (stable) and x = -sqrt(p) (unstable)."""
    prob = EquilibriumProblem(lambda x, lam, a: lam - x * x, 1)
    halves = {}
    for d in (1, -1):
        br = continue_equilibria(prob, EquilibriumSettings(ds=0.1, lam_max=1.0, direction=d), [0.0], 0.0)
        assert br.outcome is Outcome.REACHED_END, br.message
        x = br.states["x"][:, 0]
        np.testing.assert_allclose(x ** 2, br.lam, atol=1e-10)
        halves[d] = x
    assert np.all(halves[1][1:] > 0) and np.all(halves[-1][1:] < 0)


def _pitchfork(x, lam, a):
    return -x ** 3 - lam * x


def test_branch_point_on_the_trivial_branch():
    """x' = -x^3 - p x along x = 0: a branch point at p = 0 (the stability changes there), located; no fold."""
    br = continue_equilibria(EquilibriumProblem(_pitchfork, 1), EquilibriumSettings(ds=0.1, lam_min=-1.0,
                             lam_max=1.0), [0.0], -1.0)
    assert br.outcome is Outcome.REACHED_END, br.message
    assert [s.type for s in br.special] == ["BP"], br.special
    assert br.special[0].located and abs(br.special[0].lam) < 1e-9


def test_branch_point_on_the_side_branch_is_no_fold():
    """Along x = sqrt(-p) from p = -1 the curve p = -x^2 turns at (0, 0), which is the branch point: reported as
    BP, not as a fold; the branch goes on along x = -sqrt(-p).  (Near the crossing the localisation's corrections
    can land on x = 0, so the BP is allowed to be bracketed rather than located; its place is checked.)"""
    br = continue_equilibria(EquilibriumProblem(_pitchfork, 1), EquilibriumSettings(ds=0.1, ds_max=0.1,
                             max_points=40, lam_min=-1.0, lam_max=1.0), [1.0], -1.0)
    types = [s.type for s in br.special]
    assert types == ["BP"], br.special
    assert abs(br.special[0].lam) < 1e-4
    x = br.states["x"][:, 0]
    np.testing.assert_allclose(x ** 2, -br.lam, atol=1e-9)
    assert x[0] > 0 and x[-1] < 0


def cycle_pitchfork(x, lam, args):
    """The unit-circle cycle of a Hopf normal form (period 2 pi, whatever lam) times z' = lam z - z^3: along
    z = 0 the z-multiplier exp(2 pi lam) passes through +1 at lam = 0, a pitchfork of cycles (z = +-sqrt(lam))."""
    r2 = x[0] ** 2 + x[1] ** 2
    return jnp.stack([-x[1] + x[0] * (1 - r2), x[0] + x[1] * (1 - r2), lam * x[2] - x[2] ** 3])


def test_branch_point_of_cycles_is_reported():
    """A non-trivial multiplier through +1 without a fold (issue 12, item 2): a located BPC at lam = 0, where
    before the stability label just flipped."""
    from gfbjax.cont import CycleProblem, CycleSettings, continue_cycles, start_from_function

    st = CycleSettings(m=4, N=12, ds=0.1, ds_max=0.2, lam_min=-0.5, lam_max=0.5, max_points=30)
    start = start_from_function(lambda t: np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t), 0 * t], -1),
                                2 * np.pi, -0.5, st)
    br = continue_cycles(CycleProblem(cycle_pitchfork, 3), st, start)
    assert br.outcome is Outcome.REACHED_END, br.message
    assert [s.type for s in br.special] == ["BPC"], br.special
    bpc = br.special[0]
    assert bpc.located and abs(bpc.lam) < 1e-8
    assert np.all(br.stable[br.lam < -1e-9]) and not np.any(br.stable[br.lam > 1e-9])


def close_hopf_pairs(x, lam, gap):
    """Two Hopf normal forms with Hopf points at lam = 1 (omega 1.0) and lam = 1 + gap (omega 1.7)."""
    def hopf(a, b, s, w):
        r2 = a * a + b * b
        return s * a - w * b - a * r2, w * a + s * b - b * r2
    d1, d2 = hopf(x[0], x[1], lam - 1.0, 1.0)
    d3, d4 = hopf(x[2], x[3], lam - 1.0 - gap, 1.7)
    return jnp.stack([d1, d2, d3, d4])


def test_two_hopf_points_in_one_step_are_both_found():
    """Hopf points at lam = 1 and 1.03 with steps of 0.2 (points at 0.85 and 1.05): the Hopf test function changes
    sign twice within the step and ends with its old sign.  The count of eigenvalues in the right half plane
    changes by 4 without a sign change to explain it; the step is shortened until each crossing has its own.
    Before, neither Hopf point was reported (and which were depended on where the branch started)."""
    br = continue_equilibria(EquilibriumProblem(close_hopf_pairs, 4, jnp.asarray(0.03)),
                             EquilibriumSettings(ds=0.2, ds_max=0.2, lam_max=1.5), np.zeros(4), 0.05)
    hs = br.special_of("HOPF")
    assert [round(h.lam, 9) for h in hs] == [1.0, 1.03], br.special
    assert all(h.located for h in hs)
    np.testing.assert_allclose([h.omega for h in hs], [1.0, 1.7], rtol=1e-9)


def test_cycle_tests_ignore_which_small_multipliers_are_computed():
    """With a partial spectrum (Arnoldi's k leading multipliers) the smallest computed multiplier enters and leaves
    the set from point to point.  That must not change the sign of any test function: nothing crosses the unit
    circle.  Before, the factors (mu - 1) and (mu_i mu_j - 1) were negative for every small real multiplier (pair),
    so each such change flipped BPC or NS and a branch point or torus was reported where there was none (seen on
    the Brusselator with the sparse solver: a "BPC" at a torus)."""
    from gfbjax.cont._events import cycle_test_functions

    core = [1.0, 1.2 + 0.8j, 1.2 - 0.8j, 1.1, -1.3, 0.6 + 0.3j, 0.6 - 0.3j, 0.4]  # trivial first
    tails = ([], [0.05], [0.05, -0.03], [0.04 + 0.02j, 0.04 - 0.02j], [0.05, 0.04 + 0.02j, 0.04 - 0.02j])
    signs = {k: set() for k in ("PD", "BPC", "NS")}
    for tail in tails:
        t = cycle_test_functions(np.array(core + tail, complex), 1, 0.3)
        for k in signs:
            signs[k].add(np.sign(t[k]))
        assert t["UNSTABLE"] == 4  # 1.2 +- 0.8i, 1.1, -1.3
    assert all(len(v) == 1 for v in signs.values()), signs
