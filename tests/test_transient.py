"""Transient runs of the GFB-rotor system (small grid Nx=24, Nz=3: 100 states; one compiled solver for all)."""

import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import gfbjax
from gfbjax.cont import dense_jacobian
from gfbjax.model import forced_vector_field, layout, runup_vector_field, vector_field
from gfbjax.params import ParameterError
from gfbjax.analyses.signals import classify_response, spectrum
from gfbjax.analyses.transient import (
    TransientResult,
    TransientSettings,
    jacobian_coloring,
    run_up,
    simulate,
)

GRID = dict(Nx=24, Nz=3)
OMEGA = 0.3
SETTINGS = TransientSettings(rtol=1e-6, atol=1e-8, samples_per_rev=32, chunk_revs=10)


@pytest.fixture(scope="module")
def ref_params():
    return gfbjax.reference_system(**GRID).nondim().traced()


@pytest.fixture(scope="module")
def g0_params():
    return gfbjax.variation("G0", **GRID).nondim().traced()


@pytest.fixture(scope="module")
def equilibrium(g0_params):
    from gfbjax.analyses.static import solve_equilibrium

    res = solve_equilibrium(g0_params, OMEGA)
    assert res.converged and res.stable
    return np.asarray(res.state)


@pytest.fixture(scope="module")
def forced_run(ref_params, equilibrium):
    """Reference system (G6.3) at Omega_bar = 0.3 for 40 revolutions from the static equilibrium."""
    return simulate(ref_params, OMEGA, revolutions=40, s0=equilibrium, settings=SETTINGS)


def test_unbalance_phase_and_direction(ref_params, equilibrium):
    """Eq. (15a): the unbalance force on the disc is eps Omega^2 (cos Omega tau, sin Omega tau); the run-up field
    at zero acceleration is the constant-speed field; the autonomous field with the oscillator on its cycle
    (cos, sin) gives the same core rates (Eq. 19-22)."""
    p, s = ref_params, jnp.asarray(equilibrium)
    p0 = eqx.tree_at(lambda q: q.eps, p, jnp.asarray(0.0))
    lay = layout(p)
    disc_acc = slice(lay.slices["rotor"].start + 6, lay.slices["rotor"].start + 8)
    for tau, direction in ((0.0, (1.0, 0.0)), (math.pi / (2 * OMEGA), (0.0, 1.0)), (math.pi / OMEGA, (-1.0, 0.0))):
        d = forced_vector_field(tau, s, OMEGA, p) - forced_vector_field(tau, s, OMEGA, p0)
        np.testing.assert_allclose(d[disc_acc], float(p.eps) * OMEGA**2 * np.array(direction), atol=1e-14)
        np.testing.assert_allclose(runup_vector_field(tau, s, p, OMEGA, 0.0), forced_vector_field(tau, s, OMEGA, p),
                                   rtol=0, atol=1e-13)
        sa = jnp.concatenate([s, jnp.array([math.cos(OMEGA * tau), math.sin(OMEGA * tau)])])
        np.testing.assert_allclose(vector_field(sa, OMEGA, p)[:-2], forced_vector_field(tau, s, OMEGA, p), atol=1e-13)


def test_colored_jacobian_is_exact(ref_params, equilibrium):
    import jax

    fn = lambda y: runup_vector_field(1.3, y, ref_params, 0.4, 1e-3)  # noqa: E731
    rng = np.random.default_rng(1)
    y = jnp.asarray(equilibrium) + 1e-2 * rng.standard_normal(equilibrium.size)
    col = jacobian_coloring(ref_params)
    assert col.n_colors < col.n // 4
    np.testing.assert_allclose(dense_jacobian(fn, y, col), jax.jit(jax.jacfwd(fn))(y), rtol=0, atol=1e-12)


def test_balanced_rotor_returns_to_equilibrium(g0_params, equilibrium):
    """G0 at Omega_bar = 0.3, where the equilibrium is stable: a kicked journal settles back on it."""
    lay = layout(g0_params)
    s0 = equilibrium.copy()
    r = lay.slices["rotor"].start
    s0[r + 4] += 0.02  # journal velocity kick (c per tau)
    s0[r + 1] -= 0.02
    res = simulate(g0_params, OMEGA, revolutions=20, s0=s0, settings=SETTINGS)
    assert res.completed, res.message
    eq_rotor = equilibrium[lay.slices["rotor"]]
    dev0 = np.abs(res.rotor[: 2 * 32, :4] - eq_rotor[:4]).max()
    dev_end = np.abs(res.rotor[-32:, :4] - eq_rotor[:4]).max()
    assert dev_end < 0.02 * dev0
    assert np.all(np.isfinite(res.rotor)) and res.h_min.min() > 0.1


def test_unbalanced_settles_on_period1(forced_run):
    res = forced_run
    assert res.completed, res.message
    assert res.stats["steps"] > 0 and res.stats["accepted"] <= res.stats["steps"]
    assert res.tau.size == 40 * 32 + 1
    P = res.poincare(last=6)
    orbit = np.ptp(res.rotor[res.window(2), :2], axis=0).max()
    assert orbit > 1e-3  # a real 1X orbit
    assert np.abs(P[-1, :2] - P[-2, :2]).max() < 1e-3 * orbit  # Poincare points collapse
    c = classify_response(res, last=12, period_tol=1e-2, min_points=10)
    assert c.kind == "period-1", c.message


def test_forward_whirl_and_1x_spectrum(forced_run):
    """The unbalance turns from x towards y: the disc whirls forward (counter-clockwise); its spectrum peaks at 1X."""
    res = forced_run
    sl = res.window(4)
    x, y = res.x_d[sl] - res.x_d[sl].mean(), res.y_d[sl] - res.y_d[sl].mean()
    vx, vy = res.rotor[sl, 6], res.rotor[sl, 7]
    assert np.mean(x * vy - y * vx) > 0
    dtau = res.tau[1] - res.tau[0]
    s = spectrum(res.x_j[sl][:-1], dtau, OMEGA)
    assert s.peak()[0] == pytest.approx(1.0, abs=1e-9)


def test_rub_ends_run_with_finite_data(ref_params, equilibrium):
    heavy = eqx.tree_at(lambda q: q.w_ext, ref_params, jnp.asarray(8.0))  # 8 p0 R L extra load: the film gives way
    res = simulate(heavy, OMEGA, revolutions=3, s0=equilibrium, settings=SETTINGS)
    assert res.outcome == "rub", res.message
    assert np.all(np.isfinite(res.rotor)) and np.all(np.isfinite(res.h_min)) and np.all(np.isfinite(res.tau))
    assert np.all(np.isfinite(res.final_state))
    assert res.h_min[-1] == pytest.approx(SETTINGS.h_rub, abs=2e-3)
    assert res.tau[-1] < 3 * 2 * math.pi / OMEGA
    assert np.all(np.diff(res.tau) > 0)


def test_runup_and_save_load(ref_params, equilibrium, tmp_path):
    res = run_up(ref_params, 0.3, 0.36, revolutions=4, s0=equilibrium, settings=SETTINGS)
    assert res.completed, res.message
    np.testing.assert_allclose(res.speed, 0.3 + res.accel * res.tau)
    assert res.speed[-1] == pytest.approx(0.36) and res.revolutions == pytest.approx(4.0, rel=1e-9)
    path = res.save(tmp_path / "run.npz")
    back = TransientResult.load(path)
    np.testing.assert_array_equal(back.rotor, res.rotor)
    assert back.outcome == res.outcome and back.accel == res.accel and back.stats["steps"] == res.stats["steps"]


def test_settings_are_checked():
    with pytest.raises(ParameterError, match="rtol"):
        TransientSettings(rtol=0.5)
    with pytest.raises(ParameterError, match="solver"):
        TransientSettings(solver="rk4")
