"""The one Newton corrector (gfbjax.cont.newton_solve / newton_solve_host): the same transitions compiled and from
Python, vmapped members, outcomes, damping semantics.  Reference values are closed forms (square roots)."""
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from gfbjax.cont import NewtonSettings, Outcome, newton_solve, newton_solve_host


def _sqrt_problem(a):
    """x^2 = a: residual max-norm, full Newton step, by-product 2x (the derivative at x)."""
    def linearise(x):
        r = x * x - a
        return jnp.max(jnp.abs(r)), -r / (2 * x), 2 * x
    return linearise


CFG = NewtonSettings(tol=1e-12, atol_step=1e-12, rtol_step=1e-12, max_iter=30)


@pytest.mark.parametrize("driver", ["compiled", "host"])
def test_square_root_and_by_product_at_the_solution(driver):
    if driver == "compiled":
        sol = jax.jit(lambda a: newton_solve(_sqrt_problem(a), jnp.array([1.0]), CFG))(2.0)
    else:
        sol = newton_solve_host(_sqrt_problem(2.0), jnp.array([1.0]), CFG)
    assert sol.outcome is Outcome.CONVERGED
    assert abs(float(sol.x[0]) - math.sqrt(2.0)) < 1e-15
    # the by-product belongs to the returned point (the residual check evaluates there)
    assert abs(float(sol.aux[0]) - 2 * math.sqrt(2.0)) < 1e-14
    assert float(sol.residual) < 1e-15


def test_vmapped_members_keep_their_own_outcome():
    sols = jax.jit(jax.vmap(lambda a: newton_solve(_sqrt_problem(a), jnp.array([1.0]), CFG)))(
        jnp.array([4.0, 9.0, -1.0]))
    codes = [Outcome.from_code(c) for c in np.asarray(sols.code)]
    assert codes[:2] == [Outcome.CONVERGED, Outcome.CONVERGED]
    np.testing.assert_allclose(np.asarray(sols.x[:2, 0]), [2.0, 3.0], rtol=0, atol=1e-15)
    # x^2 = -1 from x = 1 steps to x = 0, where the step is infinite: NONFINITE, and x stays the last finite iterate
    assert codes[2] is Outcome.NONFINITE
    assert np.isfinite(float(sols.x[2, 0]))


def test_iteration_budget_and_divergence():
    few = NewtonSettings(tol=1e-12, atol_step=1e-12, rtol_step=1e-12, max_iter=2)
    assert newton_solve_host(_sqrt_problem(2.0), jnp.array([1.0]), few).outcome is Outcome.MAX_ITERATIONS

    def growing(x):  # steps 10, 110, 1210, ...: the third is 121 times the smallest
        return jnp.asarray(1.0), 10.0 * (jnp.abs(x) + 1.0), None

    sol = newton_solve_host(growing, jnp.array([0.0]), NewtonSettings(divergence=50.0))
    assert sol.outcome is Outcome.DIVERGED


@pytest.mark.parametrize("driver", ["compiled", "host"])
def test_damping_is_not_applied_to_a_step_that_is_already_small(driver):
    """From the solution the step is rounding noise; a damping rule that compares noise (here: always the smallest
    fraction) must not keep the corrector from converging."""
    def damping(x, dx, aux):
        return 1.0 / 64.0

    x0 = jnp.array([math.sqrt(2.0)])
    if driver == "compiled":
        sol = jax.jit(lambda x: newton_solve(_sqrt_problem(2.0), x, CFG, damping=damping))(x0)
    else:
        sol = newton_solve_host(_sqrt_problem(2.0), x0, CFG, damping=damping)
    assert sol.outcome is Outcome.CONVERGED and int(sol.iterations) <= 1


def test_python_float_damping_on_the_host():
    """A damping returning a plain Python float (not an array) is a fraction, not a bit pattern."""
    sol = newton_solve_host(_sqrt_problem(2.0), jnp.array([1.0]), CFG, damping=lambda x, dx, aux: 1.0)
    assert sol.outcome is Outcome.CONVERGED
    sol = newton_solve_host(_sqrt_problem(2.0), jnp.array([1.0]), CFG, damping=lambda x, dx, aux: 0.0)
    assert sol.outcome is Outcome.NONFINITE  # no acceptable step


def test_settings_name_the_field():
    with pytest.raises(ValueError, match="max_iter"):
        NewtonSettings(max_iter=0)
    with pytest.raises(ValueError, match="atol_step and rtol_step"):
        NewtonSettings(atol_step=0.0, rtol_step=0.0)
    with pytest.raises(ValueError, match="divergence"):
        NewtonSettings(divergence=1.0)
