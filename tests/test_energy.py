"""Energy of limit cycles (gfbjax.analyses.energy, paper Eq. 23-24): the identity W_fu = W_B, an independent polyline
evaluation of the same works from positions (not the velocity states the quadrature uses), W_cf >= 0, and the
convergence of the collocation quadrature under mesh refinement.  Small grid (Nx=16, Nz=2)."""
from __future__ import annotations

import numpy as np
import pytest

import gfbjax
from gfbjax import cont
from gfbjax.cont import _collocation as col
from gfbjax.analyses.cycles import continue_gfb_cycles, default_cycle_settings
from gfbjax.analyses.energy import branch_energy, cycle_energy, sign_changes
from gfbjax.model import layout
from gfbjax.model.reynolds import bearing_force


def _cycle(params, omega, N=16):
    st = default_cycle_settings(max_points=1, save_states=True, N=N)
    br = continue_gfb_cycles(params, omega, 1.0, st)
    assert len(br) == 1, br.message
    return cont.start_from_branch(br, 0).orbit


@pytest.fixture(scope="module")
def params():
    return gfbjax.reference_system(Nx=16, Nz=2).nondim()


@pytest.mark.parametrize("omega", [0.15, 0.3, 0.6])
def test_unbalance_work_equals_bearing_work(params, omega):
    E = cycle_energy(_cycle(params, omega), params)
    print(f"Omega {omega}: W_fu {float(E.W_fu):.6e} W_B {float(E.W_B):.6e} W_cf {float(E.W_cf):.3e} "
          f"W_cb {float(E.W_cb):.6e}")
    assert float(E.W_fu) > 0.0                       # the unbalance feeds the synchronous whirl
    assert float(E.W_cf) > 0.0                       # the foil dampers dissipate
    assert abs(float(E.W_fu - E.W_B)) <= 1e-11 * abs(float(E.W_fu))


def test_identity_on_radau_points(params):
    """A cycle computed on Radau points has x' = T f(x) exact at the Radau points, not at the Gauss points, yet the
    works were always integrated on Gauss points: on an adapted mesh the identity W_fu = W_B failed by up to
    6.9e-5 relative on a Radau branch (fresh-user review).  On the branch's own points it holds to the solution's
    accuracy (m-point Radau quadrature is exact to degree 2m - 2 only, one short of the kinetic-energy term):
    measured <= 3e-8 here, in branch_energy (from the branch's ``collocation``) and in
    FoilDesign(collocation="radau")."""
    from gfbjax.analyses.energy import _batch
    from gfbjax.design.evaluate import FoilDesign

    st = default_cycle_settings(max_points=6, save_states=True, collocation="radau")
    br = continue_gfb_cycles(params, 0.3, 0.45, st)
    assert br.collocation == "radau" and len(br) >= 6
    E = branch_energy(br, params)
    assert np.all(np.abs(E.W_fu - E.W_B) <= 1e-7 * np.abs(E.W_fu)), np.abs(E.W_fu - E.W_B) / np.abs(E.W_fu)
    s = br.states
    on_gauss = np.asarray(_batch(s["xm"], s["xi"], s["mesh"], s["T"], s["lam"], params, "gauss"))
    assert np.max(np.abs(on_gauss[:, 0] - on_gauss[:, 1]) / np.abs(on_gauss[:, 0])) > 1e-6  # the old quadrature
    ev = FoilDesign(params, 0.3, collocation="radau").evaluate(float(params.alpha_f), float(params.eta))
    assert abs(ev.energy.W_fu - ev.energy.W_B) <= 1e-7 * abs(ev.energy.W_fu)


def test_identity_rigid_rotor():
    p = gfbjax.reference_system(Nx=16, Nz=2, rotor="rigid").nondim()
    E = cycle_energy(_cycle(p, 0.3), p)
    assert float(E.W_fu) > 0.0
    assert abs(float(E.W_fu - E.W_B)) <= 1e-11 * abs(float(E.W_fu))


def test_works_against_polyline_from_positions(params):
    """W_B = -2 closed-integral F_B . dx_j and W_cf = 2 dtheta sum closed-integral c_f (dq/dtau) dq, evaluated on
    a fine resampling of the orbit with differences of the *positions* x_j and q (trapezoid), must agree with the
    quadrature of the powers built from the velocity states and the foil law."""
    omega = 0.3
    orbit = _cycle(params, omega)
    E = cycle_energy(orbit, params)
    t, X = col.evaluate(orbit, col.Scheme(4), per_interval=400)
    tau = t * float(orbit.T)
    lay = layout(params, oscillator=True)
    g = lay.grid
    F = np.array([np.asarray(bearing_force(lay.pressures(x), g.theta(params.theta0), g, 0.0)) for x in X])
    xj = np.asarray(lay.journal(X))
    WB = -2.0 * np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(xj, axis=0))
    q = np.asarray(lay.foil_deflection(X))
    c_f = float(params.eta / (params.alpha_f * omega))
    dq = np.diff(q, axis=0)
    Wcf = 2.0 * g.dtheta * c_f * np.sum(dq * dq / np.diff(tau)[:, None])
    print(f"W_B quadrature {float(E.W_B):.8e} polyline {WB:.8e}; W_cf {float(E.W_cf):.8e} polyline {Wcf:.8e}")
    assert abs(WB - float(E.W_B)) < 1e-5 * abs(float(E.W_B))
    assert abs(Wcf - float(E.W_cf)) < 1e-4 * abs(float(E.W_cf))


def test_quadrature_converges_at_collocation_order(params):
    """W_cb at N = 4, 8, 16 against N = 32 (m = 4): error ratio per halving ~2^(2m) = 256."""
    W = {N: float(cycle_energy(_cycle(params, 0.3, N), params).W_cb) for N in (4, 8, 16, 32)}
    e = [abs(W[N] - W[32]) for N in (4, 8, 16)]
    orders = np.log2(np.array(e[:-1]) / np.array(e[1:]))
    print("W_cb", W, "errors", e, "orders", orders)
    assert e[2] < 1e-9 * abs(W[32])
    assert np.all(orders > 6.0)


def test_branch_energy_matches_pointwise_and_needs_states(params):
    st = default_cycle_settings(max_points=3, save_states=True, N=16)
    br = continue_gfb_cycles(params, 0.2, 1.0, st)
    E = branch_energy(br, params)
    for i in range(len(br)):
        Ei = cycle_energy(cont.start_from_branch(br, i).orbit, params)
        assert np.isclose(E.W_cb[i], float(Ei.W_cb), rtol=1e-12)
    with pytest.raises(ValueError, match="save_states"):
        branch_energy(continue_gfb_cycles(params, 0.2, 1.0, default_cycle_settings(max_points=1, N=16)), params)


def test_sign_changes():
    lam = np.array([0.1, 0.2, 0.3, 0.4])
    assert sign_changes(lam, np.array([2.0, 1.0, -1.0, -2.0])) == [{"Omega_bar": 0.25, "from": "+"}]
    assert sign_changes(lam, np.array([1.0, 2.0, 3.0, 4.0])) == []
