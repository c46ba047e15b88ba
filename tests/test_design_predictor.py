"""The predictor of the optimised continuation (gfbjax.design.predictor, gfbjax.design.quasi_newton; issue 15,
item 3).

Analytic part: ``f(z; w) = 1 + (z0 - w)^2 + 2 (z1 - w^2)^2`` in log variables ``z = log x``, whose optimum moves
with the parameter w in closed form, ``z* = (w, w^2)`` (by hand: both squares vanish), or ``z1* = zh1`` once
``w^2`` passes the upper bound ``zh1`` (the second square only grows towards the bound).  The 1 gives the
objective a scale, as max|mu| has: the stopping rules are relative to |f|.  Cycle part: on a tiny case (16x2,
N = 8) the schedule with the predictor reaches the optima of the schedule without it, with fewer cycle solves.
"""
from __future__ import annotations

import numpy as np
import pytest

import gfbjax
from gfbjax.design.predictor import OptimumTrail, extrapolate, lagrange_weights
from gfbjax.design.quasi_newton import curvature_from_history, minimize_warm, model_decrease
from gfbjax.design.schedule import optimized_continuation
from gfbjax.params import ParameterError

ZL = np.log(np.array([0.01, 0.01]))
ZH = np.array([np.log(10.0), 0.2])  # z1 <= 0.2: on the bound from w = sqrt(0.2) = 0.447 on
H_EXACT = np.diag([2.0, 4.0])       # Hessian of f in z


def f_and_grad(w):
    """f and its gradient with respect to the physical x = exp(z), as the optimisers expect."""
    def fg(x):
        z = np.log(x)
        gz = np.array([2 * (z[0] - w), 4 * (z[1] - w ** 2)])
        return 1 + (z[0] - w) ** 2 + 2 * (z[1] - w ** 2) ** 2, gz / x
    return fg


def z_star(w):
    return np.array([w, min(w ** 2, ZH[1])])


def f_star(w):
    return 1 + 2 * (z_star(w)[1] - w ** 2) ** 2


def test_lagrange_weights():
    w = lagrange_weights(np.array([0.2, 0.3, 0.4]), 0.5)
    np.testing.assert_allclose(w, [1.0, -3.0, 3.0])
    np.testing.assert_allclose(lagrange_weights(np.array([0.3, 0.4]), 0.5), [-1.0, 2.0])
    with pytest.raises(ValueError, match="distinct"):
        lagrange_weights(np.array([0.3, 0.3]), 0.5)


def test_extrapolation_reproduces_the_moving_optimum():
    ws = np.array([0.1, 0.2, 0.3])
    zs = np.array([z_star(w) for w in ws])
    # order 2 is exact for z* = (w, w^2); the secant misses z1 by 2 h^2 = 0.02 (h = 0.1)
    np.testing.assert_allclose(extrapolate(ws, zs, 0.4, ZL, ZH, order=2), [0.4, 0.16], atol=1e-14)
    np.testing.assert_allclose(extrapolate(ws, zs, 0.4, ZL, ZH, order=1), [0.4, 0.14], atol=1e-14)
    np.testing.assert_allclose(extrapolate(ws, zs, 0.4, ZL, ZH, order=0), zs[-1])
    # a variable on its bound at the last optimum stays there, the other one moves on
    ws2 = np.array([0.4, 0.5])
    zs2 = np.array([z_star(w) for w in ws2])
    assert zs2[-1, 1] == ZH[1]
    np.testing.assert_allclose(extrapolate(ws2, zs2, 0.6, ZL, ZH, order=1), z_star(0.6), atol=1e-14)
    # the move is capped at max_move (infinity norm), then clipped to the box
    far = extrapolate(np.array([0.1, 0.2]), np.array([[0.0, 0.0], [-0.9, 0.1]]), 0.5, ZL, ZH, max_move=1.0)
    np.testing.assert_allclose(far, [-1.9, 0.2])  # linear: (-3.6, 0.4); capped: (-1.9, 0.1 + 1/9); z1 <= 0.2
    # past a jump of the optimum (a move > max_move: another local minimum) only the optima after it count
    zj = np.array([[0.0, 0.0], [-3.0, 0.1], [-3.1, 0.1]])
    np.testing.assert_allclose(extrapolate(np.array([0.1, 0.2, 0.3]), zj, 0.4, ZL, ZH), [-3.2, 0.1])
    np.testing.assert_allclose(extrapolate(np.array([0.1, 0.2]), zj[:2], 0.3, ZL, ZH), zj[1])


def test_warm_optimiser_accepts_a_good_prediction_at_once():
    w, lo, hi = 0.35, np.exp(ZL), np.exp(ZH)
    res = minimize_warm(f_and_grad(w), np.exp(z_star(w) + 1e-4), lo, hi, hessian=H_EXACT, explore=None)
    assert res.reason == "model" and res.n_evals == 1
    # with the exploratory step (default): one evaluation more, which gains nothing on a convex f
    res = minimize_warm(f_and_grad(w), np.exp(z_star(w) + 1e-4), lo, hi, hessian=H_EXACT)
    assert res.reason == "model" and res.n_evals == 2 and np.all(res.x == np.exp(z_star(w) + 1e-4))
    # a poor prediction: the Newton step of the carried (exact) model lands on the optimum
    res = minimize_warm(f_and_grad(w), np.exp(z_star(w) + [0.3, -0.2]), lo, hi, hessian=H_EXACT)
    assert res.n_evals == 2 and res.reason == "kkt"
    np.testing.assert_allclose(np.log(res.x), z_star(w), atol=1e-12)


def test_exploratory_step_catches_a_too_stiff_model():
    """A carried model 100x too stiff makes the start look converged (predicted gain 8e-6 < 1e-4 |f|); the long
    step along the descent gains 0.03, so the model is dropped and the optimum z0 = 2 is found."""
    def fg(x):
        z = np.log(x)
        return 1 + 0.01 * (z[0] - 2) ** 2 + z[1] ** 2, np.array([0.02 * (z[0] - 2), 2 * z[1]]) / x
    lo, hi, stiff = np.exp(ZL), np.exp(ZH), np.diag([100.0, 100.0])
    fooled = minimize_warm(fg, [1.0, 1.0], lo, hi, hessian=stiff, explore=None)
    assert fooled.reason == "model" and fooled.n_evals == 1
    res = minimize_warm(fg, [1.0, 1.0], lo, hi, hessian=stiff, f_rtol=1e-8)
    np.testing.assert_allclose(np.log(res.x), [2.0, 0.0], atol=1e-3)
    assert res.hessian[0, 0] < 1.0  # the model at the end is the problem's, not the stiff one


def test_warm_optimiser_cold_and_on_a_bound():
    w = 0.6  # z1* on its upper bound
    res = minimize_warm(f_and_grad(w), [1.0, 1.0], np.exp(ZL), np.exp(ZH), f_rtol=1e-10)
    assert res.reason in ("kkt", "model", "f_rtol"), res.reason
    np.testing.assert_allclose(np.log(res.x), z_star(w), atol=1e-4)
    assert res.hessian is not None and np.all(np.linalg.eigvalsh(res.hessian) > 0)
    assert model_decrease(np.zeros(2), None, np.array([False, False])) == 0.0
    B = curvature_from_history(res.history)
    assert B is not None and np.all(np.linalg.eigvalsh(B) > 0)
    with pytest.raises(ValueError, match="hessian"):
        minimize_warm(f_and_grad(w), [1.0, 1.0], np.exp(ZL), np.exp(ZH), hessian=np.eye(3))


@pytest.mark.parametrize("order", [1, 2])
def test_predictor_corrector_march_on_the_analytic_problem(order):
    """The loop of optimized_continuation on f: every optimum is the closed-form one (f within 2e-8, i.e. z
    within ~1e-4), and once the trail is long enough each speed costs one or two evaluations (the cold start at
    the first speed costs 9).  Without the exploratory step, which would add one evaluation per speed."""
    trail = OptimumTrail(ZL, ZH, order=order)
    x, evals = np.array([1.0, 1.0]), []
    for w in np.arange(0.1, 0.81, 0.05):
        if trail.omegas:
            x, _ = trail.predict(w)
        res = minimize_warm(f_and_grad(w), x, np.exp(ZL), np.exp(ZH), hessian=trail.hessian, f_rtol=1e-8,
                            explore=None)
        assert res.fun - f_star(w) <= 2e-8, (w, res.fun, res.reason)
        np.testing.assert_allclose(np.log(res.x), z_star(w), atol=2e-4)
        trail.add(w, res.x, None, res.hessian)
        evals.append(res.n_evals)
    print(f"order {order}: evaluations per speed {evals}")
    # the optima are converged to f_rtol only (z to ~1e-4), and the extrapolation weights (-1, 2) or (1, -3, 3)
    # amplify that error: a speed costs the predicted point, at most one Newton step more
    assert max(evals[3:]) <= 2
    assert evals[3:].count(1) >= len(evals[3:]) / 2


def test_predict_needs_the_gradient_method():
    p = gfbjax.reference_system(Nx=16, Nz=2).nondim()
    with pytest.raises(ParameterError, match="predict"):
        optimized_continuation(p, 0.3, 0.4, 0.05, method="pattern", predict=True)
    with pytest.raises(ParameterError, match="predict_order"):
        optimized_continuation(p, 0.3, 0.4, 0.05, predict_order=-1)


def test_schedule_with_predictor_matches_without_it():
    smooth = gfbjax.reference_system(Nx=16, Nz=2, gumbel_width=1e-3).nondim()
    # started near the optimum (alpha_f on its bound): the test is about the march, not the first speed
    kw = dict(objective="max_mu", N=8, x0=(2.0, 2.4))
    plain = optimized_continuation(smooth, 0.35, 0.45, 0.05, predict=False, **kw)
    pred = optimized_continuation(smooth, 0.35, 0.45, 0.05, predict=True, **kw)
    print("plain", plain.n_solves_per_speed, plain.stop_reasons, plain.max_mu)
    print("predictor", pred.n_solves_per_speed, pred.stop_reasons, pred.max_mu)
    assert pred.omega == pytest.approx(plain.omega)
    for a, b in zip(pred.max_mu, plain.max_mu):
        assert a <= b * (1 + 5e-3)  # as good as the plain optimum, to 0.5%
    assert pred.n_solves < plain.n_solves
    assert sum(pred.n_solves_per_speed) == pred.n_solves
    assert len(pred.stop_reasons) == len(pred.omega)


def test_warm_optimize_at_speed_keeps_an_optimum_on_the_bound():
    """optimize_at_speed(warm=True) with a stand-in design whose evaluate() checks the bounds as the real one
    does (check_foil) and whose objective wants eta as large as allowed (optimum alpha_f = 0.2, eta = 10)."""
    from types import SimpleNamespace

    from gfbjax.design.evaluate import check_foil
    from gfbjax.design.schedule import optimize_at_speed

    class Design:
        params = SimpleNamespace(alpha_f=0.1, eta=0.05)
        omega, n_solves, n_gradients, orbit = 0.3, 0, 0, None

        def evaluate(self, alpha_f, eta, gradient=False):
            alpha_f, eta = check_foil(alpha_f, eta)
            self.n_solves += 1
            mu = 0.5 + (np.log(alpha_f) - np.log(0.2)) ** 2 - 0.01 * np.log(eta)
            grad = np.array([2 * (np.log(alpha_f) - np.log(0.2)) / alpha_f, -0.01 / eta])
            return SimpleNamespace(alpha_f=alpha_f, eta=eta, W_cb=1.0, max_mu=mu, grad_max_mu=grad,
                                   grad_W_cb=-grad, orbit=None, stable=True)

    cold = optimize_at_speed(Design(), "max_mu", "gradient", (0.1, 0.05), warm=True)  # no model: L-BFGS
    assert cold.eta == 10.0 and cold.alpha_f == pytest.approx(0.2, rel=1e-2) and cold.hessian is not None
    warm = optimize_at_speed(Design(), "max_mu", "gradient", (0.21, 9.0), warm=True, hessian=cold.hessian)
    assert warm.eta == 10.0 and warm.alpha_f == pytest.approx(0.2, rel=1e-2)
    assert warm.n_solves < cold.n_solves
    with pytest.raises(ParameterError, match="warm"):
        optimize_at_speed(Design(), "max_mu", "pattern", (0.1, 0.05), warm=True)
