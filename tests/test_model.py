"""Properties of the GFB-rotor vector field (gfbjax.model): jit, vmap, grad (vs finite differences), state
layout, phase oscillator, direction of the unbalance force."""

import math

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import gfbjax
from gfbjax.model import balanced_vector_field, forced_vector_field, layout, vector_field
from gfbjax.analyses.plain import plain_bearing_steady

jax.config.update("jax_enable_x64", True)

# a small grid keeps the tests fast; the properties do not depend on it
SPEC = gfbjax.reference_system(Nx=16, Nz=3)


def _params(spec=SPEC):
    return jax.tree_util.tree_map(jnp.asarray, spec.nondim())  # float leaves as arrays (differentiable)


def _state(params, oscillator, seed=0, phase=0.3):
    """A generic state: pressures well above ambient (so every strip is loaded and max(p_m - 1, 0) is smooth
    there), foil deflected, rotor displaced and moving, oscillator on its cycle."""
    lay = layout(params, oscillator)
    g = lay.grid
    rng = np.random.default_rng(seed)
    P = 1.2 + 0.1 * rng.random((g.n_theta, g.Nz))
    q = 0.01 + 0.01 * rng.random(g.n_theta)
    r = 0.1 * rng.standard_normal(lay.n_rotor)
    osc = jnp.array([math.cos(phase), math.sin(phase)]) if oscillator else None
    return lay.pack(jnp.asarray(P), jnp.asarray(q), jnp.asarray(r), osc)


@pytest.mark.parametrize("fn, osc", [(vector_field, True), (balanced_vector_field, False)])
def test_jit_and_vmap(fn, osc):
    params = _params()
    s = _state(params, osc)
    eager = fn(s, 1.3, params)
    assert eager.shape == s.shape and np.all(np.isfinite(eager))
    np.testing.assert_allclose(jax.jit(fn)(s, 1.3, params), eager, rtol=1e-12, atol=1e-12)
    omegas = jnp.array([0.5, 1.3, 2.0])
    batched = jax.vmap(fn, in_axes=(None, 0, None))(s, omegas, params)
    for k, om in enumerate(omegas):
        np.testing.assert_allclose(batched[k], fn(s, om, params), rtol=1e-12, atol=1e-12)
    states = jnp.stack([_state(params, osc, seed=k) for k in range(3)])
    batched = jax.jit(jax.vmap(fn, in_axes=(0, None, None)))(states, 1.3, params)
    for k in range(3):
        np.testing.assert_allclose(batched[k], fn(states[k], 1.3, params), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("fn, osc", [(vector_field, True), (balanced_vector_field, False)])
def test_grad_wrt_params_matches_finite_differences(fn, osc):
    params = _params()
    s = _state(params, osc)
    weights = jnp.asarray(np.random.default_rng(1).standard_normal(s.shape))
    omega = 1.3

    # differentiate w.r.t. alpha_f and eta only: an equinox filter spec selects them
    spec = jax.tree_util.tree_map(lambda _: False, params)
    spec = eqx.tree_at(lambda p: (p.alpha_f, p.eta), spec, (True, True))
    diff, static = eqx.partition(params, spec)

    def objective(d):
        return jnp.dot(weights, fn(s, omega, eqx.combine(d, static)))

    grads = jax.jit(jax.grad(objective))(diff)
    for name in ("alpha_f", "eta"):
        x0 = float(getattr(params, name))
        h = 1e-6 * x0

        def at(v, name=name):
            return float(objective(eqx.tree_at(lambda d: getattr(d, name), diff, jnp.asarray(v))))

        fd = (at(x0 + h) - at(x0 - h)) / (2 * h)
        g = float(getattr(grads, name))
        assert abs(fd) > 1e-3  # the parameter does act on this state
        assert g == pytest.approx(fd, rel=1e-6), name
    # the other floats get no gradient through the filter
    assert grads.zeta is None and grads.kappa is None


def test_state_layout_round_trip():
    for spec, n_rotor in ((SPEC, 8), (gfbjax.validation_case(Nx=16, Nz=3), 4)):
        params = _params(spec)
        for osc in (False, True):
            lay = layout(params, osc)
            g = lay.grid
            assert g.n_theta == params.Nx - 1  # foil bearing: p = 1 at both foil ends
            s = jnp.asarray(np.random.default_rng(2).standard_normal(lay.n))
            P, q, r = lay.pressures(s), lay.foil_deflection(s), lay.rotor(s)
            o = lay.oscillator_state(s)
            assert P.shape == (params.Nx - 1, params.Nz)
            assert q.shape == (params.Nx - 1,)
            assert r.shape == (n_rotor,)
            assert o.shape == ((2,) if osc else (0,))
            assert lay.n == P.size + q.size + r.size + o.size
            np.testing.assert_array_equal(lay.pack(P, q, r, o if osc else None), s)
            np.testing.assert_array_equal(lay.journal(s), r[:2])
            # pressures are stored theta-major: entry (i, j) is s[i * Nz + j]
            assert float(P[2, 1]) == float(s[2 * params.Nz + 1])
            # views work on a batch of states
            S = jnp.stack([s, 2 * s])
            assert lay.pressures(S).shape == (2, params.Nx - 1, params.Nz)
            np.testing.assert_array_equal(lay.rotor(S)[1], 2 * r)


def test_oscillator_solution_is_cos_sin():
    """Integrating the last two equations of the autonomous system from (1, 0) gives (cos W tau, sin W tau);
    from off the cycle the radius returns to 1."""
    params = _params()
    s = _state(params, True)
    omega = 1.7

    def rhs(tau, u, args):
        return vector_field(s.at[-2:].set(u), omega, params)[-2:]

    period = 2 * math.pi / omega
    ts = jnp.linspace(0.0, 3 * period, 13)
    sol = diffrax.diffeqsolve(diffrax.ODETerm(rhs), diffrax.Tsit5(), 0.0, float(ts[-1]), 0.01,
                              jnp.array([1.0, 0.0]), saveat=diffrax.SaveAt(ts=ts),
                              stepsize_controller=diffrax.PIDController(rtol=1e-11, atol=1e-12), max_steps=100_000)
    np.testing.assert_allclose(sol.ys[:, 0], np.cos(omega * np.asarray(ts)), atol=1e-8)
    np.testing.assert_allclose(sol.ys[:, 1], np.sin(omega * np.asarray(ts)), atol=1e-8)
    off = diffrax.diffeqsolve(diffrax.ODETerm(rhs), diffrax.Tsit5(), 0.0, 20.0, 0.01, jnp.array([0.3, 0.0]),
                              stepsize_controller=diffrax.PIDController(rtol=1e-9, atol=1e-10), max_steps=100_000)
    assert float(jnp.hypot(*off.ys[-1])) == pytest.approx(1.0, abs=1e-6)


def test_unbalance_force_rotates_with_shaft():
    """The unbalance acceleration of the disc is eps W^2 (cos phi, sin phi) and turns towards +theta (from x to
    y) as the phase grows: the direction in which the shaft drags the gas film (a journal displaced along +x feels
    a gas force with a +y component)."""
    params = _params()
    lay = layout(params, True)
    omega = 1.5
    eps = float(params.eps)
    assert eps > 0.0
    balanced = eqx.tree_at(lambda p: p.eps, params, jnp.asarray(0.0))
    sl = lay.slices["rotor"]
    for phi in (0.0, 0.5 * math.pi, 0.25 * math.pi, math.pi):
        s = _state(params, True, phase=phi)
        d = (vector_field(s, omega, params) - vector_field(s, omega, balanced))[sl]
        # rotor rates [x_j', y_j', x_d', y_d', x_j'', y_j'', x_d'', y_d'']: only the disc accelerations change
        np.testing.assert_allclose(d[:6], 0.0, atol=1e-14)
        np.testing.assert_allclose(d[6:], eps * omega**2 * np.array([math.cos(phi), math.sin(phi)]), rtol=1e-12,
                                   atol=1e-15)
    # non-autonomous form: phase = omega tau, so a quarter period later the force points along +y
    s = _state(params, False)
    bal = lambda tau: forced_vector_field(tau, s, omega, balanced)  # noqa: E731
    for tau, direction in ((0.0, (1.0, 0.0)), (0.5 * math.pi / omega, (0.0, 1.0))):
        d = (forced_vector_field(tau, s, omega, params) - bal(tau))[lay.slices["rotor"]][6:]
        np.testing.assert_allclose(d, eps * omega**2 * np.array(direction), atol=1e-12)
    # the film is dragged the same way: +x displacement -> force with +y component (positive attitude)
    r = plain_bearing_steady(1.0, 0.1, 0.0, 0.5, 16, 4)
    assert float(r.force[1]) > 0.0
