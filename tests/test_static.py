"""Static equilibria of the GFB-rotor system (gfbjax.analyses.static): force balance, foil deflection, contact outcome.

The checks recompute the gas force and the strip mean pressures from the *returned pressure field* with NumPy
quadrature written here (trapezoid rule in theta over the Nx + 1 nodes and in z over the Nz + 1 nodes), not with
gfbjax's own force routine, and compare them with the loads the equilibrium must carry.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import gfbjax
from gfbjax.analyses.static import solve_equilibrium

jax.config.update("jax_enable_x64", True)


def _arrays(params):
    """Params with its float leaves as JAX arrays (``newton_solve`` is an ``eqx.filter_jit`` function: Python-float
    leaves would recompile it for every new value; 10-40 s each)."""
    return params.traced()


def _gas_force(theta, z, pressure):
    """Gas force on the journal (F_X, F_Y) over the whole length [p0 R L], from p/p0 on all nodes.

    F = -int_0^{2 pi} int_0^1 max(p - 1, 0) (cos th, sin th) dz dth; the half length 0..1/2 counts twice."""
    g = np.maximum(pressure - 1.0, 0.0)
    col = 2.0 * np.trapezoid(g, z, axis=1)  # integral over the full length, per circumferential node
    return -np.array([np.trapezoid(col * np.cos(theta), theta), np.trapezoid(col * np.sin(theta), theta)])


def _strip_mean_gauge(z, pressure):
    """Mean gauge pressure p_m - 1 of each circumferential node over the bearing length."""
    return 2.0 * np.trapezoid(pressure - 1.0, z, axis=1)


CASES = {
    # name: (spec, omega, w)
    "reference_w0": (gfbjax.reference_system(), 1.0, 0.0),
    "reference_w0.3": (gfbjax.reference_system(), 2.0, 0.3),
    "reference_af1": (gfbjax.reference_system(alpha_f=1.0), 1.5, 0.2),
    "validation10N": (gfbjax.validation_case(10.0), 1.0, 0.0),
}


@pytest.fixture(scope="module")
def equilibria():
    out = {}
    for name, (spec, omega, w) in CASES.items():
        params = spec.nondim()
        out[name] = (params, omega, w, solve_equilibrium(_arrays(params), omega, w))
    return out


@pytest.mark.parametrize("name", list(CASES))
def test_force_balance(equilibria, name):
    params, omega, w, r = equilibria[name]
    assert r.outcome == "converged", r.message
    assert r.pressure.shape == (params.Nx + 1, params.Nz + 1)
    # the grid the result reports is the one of docs/model.md: foil ends theta0, theta0 + 2 pi; z from edge to mid-plane
    assert r.theta[0] == pytest.approx(params.theta0) and r.theta[-1] == pytest.approx(params.theta0 + 2 * math.pi)
    assert r.z[0] == 0.0 and r.z[-1] == pytest.approx(0.5)
    np.testing.assert_allclose(r.pressure[:, 0], 1.0)  # bearing edge
    np.testing.assert_allclose(r.pressure[[0, -1], :], 1.0)  # foil ends
    F = _gas_force(r.theta, r.z, r.pressure)
    zeta, sigma, mass_ratio = params.zeta, params.sigma, params.mass_ratio
    w_ext = 2.0 * w  # W/(p0 R L) of the specific load W/(p0 L D)
    weight = sigma * (1.0 + mass_ratio) + zeta * w_ext  # journal's share of gravity + extra load, per zeta
    assert weight > 0.0
    # zeta F_BY = sigma (1 + m_d/(2 m_j)) + zeta w_ext and F_BX = 0, to the Newton tolerance (residual ~1e-13)
    assert abs(zeta * F[1] - weight) < 1e-9 * max(1.0, weight)
    assert abs(zeta * F[0]) < 1e-9
    # the journal sits below the centre (load downwards) and ahead in the direction of rotation (+theta)
    assert r.y_j < 0.0 and r.h_min > 0.0
    assert np.all(np.isfinite(r.state))


@pytest.mark.parametrize("name", ["reference_w0.3", "reference_af1", "validation10N"])
def test_static_foil_deflection(equilibria, name):
    params, omega, w, r = equilibria[name]
    assert r.converged
    gauge = _strip_mean_gauge(r.z, r.pressure)
    expected = params.alpha_f * np.maximum(gauge, 0.0)  # q = max(p_m - 1, 0) / k_f with k_f = 1 / alpha_f
    np.testing.assert_allclose(r.foil, expected, rtol=0.0, atol=1e-10)
    np.testing.assert_array_equal(r.foil[[0, -1]], 0.0)  # clamped ends
    # both regimes of Gumbel's condition occur: loaded strips deflect, sub-ambient strips stay at q = 0
    interior = gauge[1:-1]
    assert np.any(interior > 1e-3) and np.any(interior < -1e-6)
    assert np.all(r.foil[1:-1][interior < 0.0] == 0.0)
    assert r.foil.max() > 1e-3 * params.alpha_f


def test_contact_outcome_has_no_nan():
    """A huge load at a very low speed on a stiff foil: the bearing cannot carry it.  The result must say so
    (``contact`` or ``no_convergence``), carry only part of the load, and contain no NaN anywhere."""
    params = _arrays(gfbjax.reference_system(alpha_f=0.01).nondim())
    r = solve_equilibrium(params, 0.05, 20.0)
    assert r.outcome in ("contact", "no_convergence")
    assert not r.converged
    assert 0.0 <= r.load_fraction < 1.0
    assert isinstance(r.message, str) and r.message
    for key, value in vars(r).items():
        if isinstance(value, np.ndarray):
            assert not np.any(np.isnan(value)), key
        elif isinstance(value, float):
            assert not math.isnan(value), key
    summary = r.summary(gfbjax.reference_system(alpha_f=0.01))
    assert all(not (isinstance(v, float) and math.isnan(v)) for v in summary.values())


def test_newton_from_a_converged_equilibrium_stops_at_once():
    """Started at its own solution the damped static Newton converges in one step: the damping test compares
    rounding noise there and must not be applied (it used to pick the 1/64 fraction until the iteration budget)."""
    from gfbjax.analyses.static import newton_solve

    params = gfbjax.reference_system(Nx=16, Nz=2).nondim()
    eq = solve_equilibrium(params, 0.3)
    assert eq.converged
    sol = newton_solve(jnp.asarray(eq.state), jnp.asarray(0.3), params.traced())
    assert bool(sol.converged) and int(sol.iterations) <= 1
    assert float(sol.residual) < 1e-9


def test_system_load_is_carried_by_the_static_solve():
    """SystemSpec.load (in params.w_ext) is part of the load a static solve carries: the equilibrium of a system
    with load L equals that of the unloaded system with the same extra load given to the solver (found by a
    sweep: it used to be dropped, so sweeping 'load' changed nothing)."""
    import gfbjax
    from gfbjax.analyses.static import solve_equilibrium

    loaded = gfbjax.reference_system(Nx=16, Nz=2, load=5.0)
    plain = gfbjax.reference_system(Nx=16, Nz=2)
    w = 5.0 / (plain.p0 * plain.L * 2 * plain.R)  # W / (p0 L D)
    a = solve_equilibrium(loaded.nondim(), 0.3)
    b = solve_equilibrium(plain.nondim(), 0.3, w)
    assert a.converged and b.converged
    assert a.w == pytest.approx(w, rel=1e-12) and b.w == pytest.approx(w, rel=1e-12)
    np.testing.assert_allclose(a.state, b.state, atol=1e-9)
    assert a.h_min < solve_equilibrium(plain.nondim(), 0.3).h_min  # the load pushes the journal into the film
