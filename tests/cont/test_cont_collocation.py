"""Collocation BVP: analytic Stuart-Landau cycle, condensed vs dense Newton step,
mesh-refinement order on Van der Pol."""
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gfbjax.cont import Outcome
from gfbjax.cont import _collocation as col
from gfbjax.cont import _floquet as floquet
from cont_systems import correct, stuart_landau, van_der_pol

W = 2.0


def _sl_guess(lam, scheme, N):
    # deliberately wrong amplitude, centre, ellipticity and period
    return col.orbit_from_function(
        lambda t: np.stack([0.8 * np.cos(2 * np.pi * t) + 0.05, 0.6 * np.sin(2 * np.pi * t)], 1),
        2 * np.pi / W * 1.05, lam, scheme, col.uniform_mesh(N))


def test_stuart_landau_cycle_and_multipliers():
    lam = 0.5
    sch = col.Scheme(4)
    o = _sl_guess(lam, sch, 10)
    res = correct(stuart_landau, jnp.asarray(W), o, col.natural_constraint(o, lam))
    assert res.converged and res.iterations <= 8
    T = 2 * np.pi / W
    assert abs(float(res.x.T) - T) < 1e-7
    r = np.hypot(np.asarray(res.x.xm[:, 0]), np.asarray(res.x.xm[:, 1]))
    assert np.max(np.abs(r - np.sqrt(lam))) < 1e-8
    G = np.asarray(col.transfer_matrices(stuart_landau, jnp.asarray(W), res.x, sch))
    mu = floquet.multipliers_periodic(G).multipliers
    assert abs(mu[0] - 1.0) < 1e-9                       # trivial multiplier
    assert abs(mu[1] - np.exp(-2 * lam * T)) < 1e-8      # exp(-2 lam T)


def test_newton_result_reports_failure_instead_of_nan():
    sch = col.Scheme(3)
    o = _sl_guess(0.5, sch, 6)
    res = correct(stuart_landau, jnp.asarray(W), o, col.natural_constraint(o, 0.5), max_iter=1)
    assert not res.converged and res.outcome is Outcome.MAX_ITERATIONS
    assert np.all(np.isfinite(np.asarray(res.x.to_flat())))


@pytest.mark.parametrize("m", [2, 3])
def test_condensed_step_equals_dense_step(m):
    sch = col.Scheme(m)
    rng = np.random.default_rng(m)
    o = _sl_guess(0.3, sch, 5)
    # exercise every row of the bordered system: pseudo-arclength row with a random direction
    v = o.from_flat(jnp.asarray(rng.normal(size=o.to_flat().shape)))
    base = o.from_flat(o.to_flat() + 0.01 * jnp.asarray(rng.normal(size=o.to_flat().shape)))
    con = col.palc_constraint(base, v, 0.02, ref=base)
    d1 = col.step_and_tangent(stuart_landau, jnp.asarray(W), o, con, sch)[0].to_flat() - o.to_flat()
    d2 = col.dense_newton_step(stuart_landau, jnp.asarray(W), o, con, sch).to_flat()
    assert float(jnp.max(jnp.abs(d1 - d2))) < 1e-11 * (1 + float(jnp.max(jnp.abs(d2))))
    assert float(jnp.max(jnp.abs(d2))) > 1e-3   # a real step, not a trivial one


MU = 1.0


@pytest.fixture(scope="module")
def vdp_reference():
    """Van der Pol (mu=1) period by scipy DOP853 (rtol 1e-13) with event location;
    the literature value is T = 6.66328685933 (e.g. Strogatz / many AUTO demos)."""
    ev = lambda t, y: y[1]
    ev.direction = -1
    f = lambda t, y: [y[1], MU * (1 - y[0] ** 2) * y[1] - y[0]]
    s = solve_ivp(f, (0, 60), [2.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-13, events=ev,
                  dense_output=True)
    te = s.t_events[0]
    T = te[-1] - te[-2]
    t = np.linspace(te[-2], te[-1], 400)
    return T, t, s.sol(t).T


def test_vdp_period_literature(vdp_reference):
    assert abs(vdp_reference[0] - 6.66328685933) < 1e-9


@pytest.mark.parametrize("m,Ns", [(2, (8, 16, 32)), (3, (32, 64))])
def test_mesh_refinement_order(vdp_reference, m, Ns):
    """Mesh-node superconvergence of Gauss collocation: period error O(h^{2m})."""
    T_ref, t, x = vdp_reference
    sch = col.Scheme(m)
    errs = []
    for N in Ns:
        o = col.orbit_from_samples(t, x, T_ref * 1.01, 0.0, sch, col.uniform_mesh(N))
        res = correct(van_der_pol, jnp.asarray(MU), o, col.natural_constraint(o, 0.0), max_iter=15)
        assert res.converged
        errs.append(abs(float(res.x.T) - T_ref))
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    print(f"m={m} N={Ns} period errors={errs} orders={orders}")
    assert np.all(orders > 2 * m - 0.7), (errs, orders)
