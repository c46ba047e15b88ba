"""Tests of gfbjax.design.optimizers: pattern search (paper Appendix A2, MATLAB GPS 2N) and the optax bounded minimiser."""

import math

import numpy as np
import optax
import pytest

from gfbjax.design.optimizers import (
    from_unconstrained,
    from_unconstrained_derivative,
    minimize_bounded,
    pattern_search,
    to_unconstrained,
)


class SolverFailed(RuntimeError):
    """Stand-in for an objective's "could not evaluate here" error."""


def sq_dist(c):
    c = np.asarray(c, dtype=float)
    return lambda x: float(np.sum((x - c) ** 2))


# ---------------------------------------------------------------------------------------------------------------
# pattern search


def test_gps_quadratic_reaches_minimum():
    A = np.array([[2.0, 0.5], [0.5, 1.0]])
    c = np.array([0.3, -0.7])
    r = pattern_search(lambda x: float((x - c) @ A @ (x - c)), [2.0, 1.5], [-3.0, -3.0], [3.0, 3.0], mesh_tol=1e-6)
    assert r.reason == "mesh_tol"
    assert r.mesh < 1e-6
    np.testing.assert_allclose(r.x, c, atol=1e-5)
    assert r.n_evals == len(r.history) == r.fs.size
    assert len(r.trace) == r.n_iter + 1
    assert np.all(np.diff(r.trace) <= 0)
    assert r.fun == min(r.fs)
    assert r.n_failed == 0


def test_gps_poll_order_expansion_contraction():
    # f = |x - [3, 0]|^2 from x0 = [0, 0], mesh0 = 1, directions e1, e2, -e1, -e2 (A2 rules, by hand):
    #   start:        [0, 0] (f = 9, accepted)
    #   it 1, m = 1:  [1, 0] f = 4 < 9 -> success, stop polling, m = 2
    #   it 2, m = 2:  [3, 0] f = 0 -> success, m = 4
    #   it 3, m = 4:  [7, 0], [3, 4], [-1, 0], [3, -4] all f = 16 -> fail, m = 2
    #   it 4, m = 2:  [5, 0], [3, 2], [1, 0], [3, -2] all f = 4 -> fail, m = 1
    #   it 5, m = 1:  [4, 0], [3, 1], [2, 0], [3, -1] -> fail, m = 0.5; then only contractions.
    # m after it 2 is 4 = 2^2 and halves each iteration: m < 1e-6 first after 22 more (2^2 * 2^-22 < 1e-6 <
    # 2^2 * 2^-21), so 24 iterations and 1 + 2 + 22 * 4 = 91 evaluations.
    r = pattern_search(sq_dist([3.0, 0.0]), [0.0, 0.0], [-10.0, -10.0], [10.0, 10.0], mesh0=1.0)
    expected = [[0, 0], [1, 0], [3, 0],
                [7, 0], [3, 4], [-1, 0], [3, -4],
                [5, 0], [3, 2], [1, 0], [3, -2],
                [4, 0], [3, 1], [2, 0], [3, -1]]
    np.testing.assert_array_equal(r.xs[:15], expected)
    assert [e.iteration for e in r.history[:7]] == [0, 1, 2, 3, 3, 3, 3]
    assert [e.accepted for e in r.history[:7]] == [True, True, True, False, False, False, False]
    assert r.trace[:4] == [9.0, 4.0, 0.0, 0.0]
    assert (r.reason, r.n_iter, r.n_evals) == ("mesh_tol", 24, 91)
    assert r.mesh == 2.0 ** -20
    np.testing.assert_array_equal(r.x, [3.0, 0.0])


def test_gps_projects_onto_bounds():
    # minimum [5, 5] outside the box [0, 2] x [0, 1]; by hand from [0.5, 0.5]:
    #   it 1, m = 1: [1.5, 0.5] success;  it 2, m = 2: [3.5 -> 2, 0.5] success;
    #   it 3, m = 4: +e1 projects onto [2, 0.5] itself (skipped), +e2: [2, 4.5 -> 1] success;
    #   it 4, m = 8: +e1, +e2 skipped, -e1: [-6 -> 0, 1], -e2: [2, -7 -> 0], both worse.
    lo, hi = np.array([0.0, 0.0]), np.array([2.0, 1.0])
    r = pattern_search(sq_dist([5.0, 5.0]), [0.5, 0.5], lo, hi)
    np.testing.assert_array_equal(r.xs[:6], [[0.5, 0.5], [1.5, 0.5], [2, 0.5], [2, 1], [0, 1], [2, 0]])
    np.testing.assert_array_equal(r.x, [2.0, 1.0])
    assert r.reason == "mesh_tol"
    assert np.all(r.xs >= lo) and np.all(r.xs <= hi)
    assert not any(np.array_equal(x, [2.0, 1.0]) for x in r.xs[4:])  # the corner is never re-evaluated


def test_gps_failures_are_infinite_and_counted():
    def f(x):
        if x[0] < 0.0:
            raise SolverFailed("no cycle")
        if x[1] > 1.5:
            return math.nan
        return float((x[0] - 0.5) ** 2 + (x[1] - 1.0) ** 2)

    r = pattern_search(f, [0.2, 0.2], [-2.0, -2.0], [2.0, 2.0], failures=(SolverFailed,))
    np.testing.assert_allclose(r.x, [0.5, 1.0], atol=1e-5)
    failed = [e for e in r.history if e.failure is not None]
    assert r.n_failed == len(failed) > 0
    assert any(e.failure.startswith("SolverFailed") for e in failed)
    assert any(e.failure == "nan" for e in failed)
    assert all(e.f == math.inf and not e.accepted for e in failed)
    assert r.n_evals == len(r.history)


def test_gps_unlisted_exception_propagates():
    def f(x):
        raise SolverFailed("boom")

    with pytest.raises(SolverFailed):
        pattern_search(f, [0.0, 0.0], [-1.0, -1.0], [1.0, 1.0])


def test_gps_limits_and_interrupt():
    f = sq_dist([0.3, -0.2])
    r = pattern_search(f, [0.0, 0.0], [-1.0, -1.0], [1.0, 1.0], max_evals=7)
    assert (r.reason, r.n_evals) == ("max_evals", 7)
    r = pattern_search(f, [0.0, 0.0], [-1.0, -1.0], [1.0, 1.0], max_iter=3)
    assert (r.reason, r.n_iter, len(r.trace)) == ("max_iter", 3, 4)

    calls = []

    def g(x):
        if len(calls) == 5:
            raise KeyboardInterrupt
        calls.append(x)
        return f(x)

    r = pattern_search(g, [0.0, 0.0], [-1.0, -1.0], [1.0, 1.0])
    assert r.reason == "interrupted"
    assert r.n_evals == 5
    assert r.fun == min(f(x) for x in calls)


def test_gps_step_and_function_tolerance():
    # successes continue at small mesh since 1/3 is not on any binary mesh
    f = sq_dist([1.0 / 3.0, 0.0])
    r = pattern_search(f, [0.0, 0.0], [-1.0, -1.0], [1.0, 1.0], step_tol=1e-3)
    assert r.reason == "step_tol" and r.mesh < 1e-3
    # pattern scale 10: steps are 10x the mesh, so the step test fails while the function test passes
    r = pattern_search(f, [0.0, 0.0], [-1.0, -1.0], [1.0, 1.0], mesh0=0.1, scale=[10.0, 10.0], step_tol=1e-3,
                       f_tol=1.0)
    assert r.reason == "f_tol" and r.mesh < 1e-3


def test_gps_callback_and_progress():
    seen = []

    def cb(it, x, f):
        seen.append(it)
        return it == 4

    r = pattern_search(sq_dist([0.3, -0.2]), [0.0, 0.0], [-1.0, -1.0], [1.0, 1.0], callback=cb, progress=True)
    assert seen == [1, 2, 3, 4]
    assert (r.reason, r.n_iter) == ("callback", 4)


@pytest.mark.parametrize("kwargs, match", [
    (dict(x0=[2.0, 0.0]), r"x0\[0\] = 2 outside"),
    (dict(lo=[-1.0, 1.0]), r"lo\[1\] = 1 must be < hi\[1\] = 1"),
    (dict(mesh0=0.0), r"mesh0 must be .* \(0, inf\)"),
    (dict(max_iter=0), r"max_iter must be an integer in \[1, inf\)"),
    (dict(contraction=1.0), r"contraction must be in \(0, 1\)"),
    (dict(hi=[1.0]), r"hi must have 2 entries"),
])
def test_gps_bad_input(kwargs, match):
    calls = []
    args = dict(x0=[0.0, 0.0], lo=[-1.0, -1.0], hi=[1.0, 1.0]) | kwargs
    with pytest.raises(ValueError, match=match):
        pattern_search(lambda x: calls.append(x) or 0.0, args.pop("x0"), args.pop("lo"), args.pop("hi"), **args)
    assert calls == []


# ---------------------------------------------------------------------------------------------------------------
# reparametrisation and minimize_bounded

LO = np.array([0.005, 1e-4])
HI = np.array([2.0, 10.0])
XMIN = np.array([0.3, 0.05])


def log_quadratic(x):
    """Quadratic in log x with minimum XMIN; value and gradient w.r.t. x."""
    r = np.log(x / XMIN)
    return float(np.sum(r ** 2)), 2.0 * r / x


def test_unconstrained_round_trip_and_range():
    x = np.array([0.0051, 9.99])
    np.testing.assert_allclose(from_unconstrained(to_unconstrained(x, LO, HI), LO, HI), x, rtol=1e-12)
    z = np.array([-0.7, 2.3])
    np.testing.assert_allclose(to_unconstrained(from_unconstrained(z, LO, HI), LO, HI), z, rtol=1e-12)
    np.testing.assert_allclose(from_unconstrained([0.0, 0.0], LO, HI), np.sqrt(LO * HI), rtol=1e-12)
    x_far = from_unconstrained([-60.0, 60.0], LO, HI)
    assert np.all(x_far >= LO) and np.all(x_far <= HI)


def test_unconstrained_derivative_matches_finite_differences():
    h = 1e-6
    for z in (np.array([-1.3, 0.4]), np.array([3.0, -4.5])):
        fd = np.array([(from_unconstrained(z + h * e, LO, HI) - from_unconstrained(z - h * e, LO, HI))[i] / (2 * h)
                       for i, e in enumerate(np.eye(2))])
        np.testing.assert_allclose(from_unconstrained_derivative(z, LO, HI), fd, rtol=1e-7)


def test_minimize_bounded_log_quadratic():
    r = minimize_bounded(log_quadratic, [0.01, 5.0], LO, HI, max_iter=800)
    assert r.reason in ("g_tol", "f_rtol")
    np.testing.assert_allclose(r.x, XMIN, rtol=1e-4)
    assert r.n_evals == r.n_grads == len(r.history)
    assert len(r.trace) == r.n_iter + 1 and np.all(np.diff(r.trace) <= 0)
    assert r.fun == min(r.fs)  # best seen, not last
    np.testing.assert_array_equal(r.x, r.xs[np.argmin(r.fs)])


def test_minimize_bounded_backtracks_failures():
    # minimum x0 = 0.3 lies beyond the failure edge x0 > 0.2: the optimiser must halve back and stay below it
    def fg(x):
        if x[0] > 0.2:
            raise SolverFailed("unstable")
        return log_quadratic(x)

    r = minimize_bounded(fg, [0.05, 1.0], LO, HI, optimizer=optax.sgd(0.5), max_iter=60,
                         failures=(SolverFailed,))
    assert r.n_failed > 0 and r.n_evals == len(r.history)
    assert 0.15 < r.x[0] <= 0.2
    h = r.history
    i = next(k for k, e in enumerate(h) if e.failure is not None)
    z_good, dz = h[i - 1].z, h[i].z - h[i - 1].z
    j = 1
    while i + j < len(h) and h[i + j].iteration == h[i].iteration:
        np.testing.assert_allclose(h[i + j].z, z_good + 0.5 ** j * dz, rtol=1e-12)
        j += 1
    assert all(e.f == math.inf and not e.accepted for e in h if e.failure is not None)


def test_minimize_bounded_start_failed_and_interrupt():
    r = minimize_bounded(lambda x: (math.nan, np.zeros(2)), [0.1, 0.1], LO, HI)
    assert (r.reason, r.n_evals, r.fun) == ("start_failed", 1, math.inf)

    calls = []

    def fg(x):
        if len(calls) == 4:
            raise KeyboardInterrupt
        calls.append(x)
        return log_quadratic(x)

    r = minimize_bounded(fg, [0.1, 0.1], LO, HI, progress=True)
    assert (r.reason, r.n_evals, r.n_iter) == ("interrupted", 4, 4)
    assert r.fun == min(log_quadratic(x)[0] for x in calls)


@pytest.mark.parametrize("kwargs, match", [
    (dict(lo=[0.0, 1e-4]), r"lo\[0\] = 0 must be in \(0, inf\)"),
    (dict(hi=[2.0, 1e-4]), r"lo\[1\] = 0.0001 must be < hi\[1\]"),
    (dict(x0=[2.0, 1.0]), r"x0\[0\] = 2 outside its bounds \(lo, hi\)"),
    (dict(max_iter=0), r"max_iter must be an integer in \[1, inf\)"),
    (dict(learning_rate=-0.1), r"learning_rate must be .* \(0, inf\)"),
    (dict(patience=0), r"patience must be an integer in \[1, inf\)"),
])
def test_minimize_bounded_bad_input(kwargs, match):
    calls = []
    args = dict(x0=[0.1, 0.1], lo=LO, hi=HI) | kwargs
    with pytest.raises(ValueError, match=match):
        minimize_bounded(lambda x: calls.append(x) or log_quadratic(x), args.pop("x0"), args.pop("lo"),
                         args.pop("hi"), **args)
    assert calls == []
