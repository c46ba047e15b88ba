"""Implicit sensitivities of W_cb and of the leading Floquet multiplier modulus with respect to the foil
properties (gfbjax.design.evaluate, the implicit derivatives of gfbjax.cont), against central finite differences of re-converged cycles;
the sparse path against the dense one.  Small grid (Nx=16, Nz=2), Omega_bar = 0.3.

Both linear solvers use the adjoint mode by default (one transposed solve per objective); a second dense design
forces the tangent mode (one solve per design variable), and the sparse adjoint is checked against the dense one
and against the sparse tangent mode.

Measured (2-core CPU): implicit vs central differences (h = 1e-4 alpha_f, 1e-5 eta) agree to 5e-9 (W_cb) and
4e-7 (max|mu|) relative; sparse and dense implicit derivatives agree to ~1e-13.
"""
from __future__ import annotations

import numpy as np
import pytest

import gfbjax
from gfbjax.cont import DenseCondensation, SparseSweep
from gfbjax.design.evaluate import FoilDesign
from gfbjax.params import ParameterError

A, E = 0.1, 0.05


@pytest.fixture(scope="module")
def params():
    return gfbjax.reference_system(Nx=16, Nz=2).nondim()


@pytest.fixture(scope="module")
def dense(params):
    d = FoilDesign(params, 0.3, linear_solver=DenseCondensation())
    return d, d.evaluate(A, E, gradient=True)


def test_gradients_against_central_differences(dense):
    d, ev = dense
    for k, h in ((0, 1e-4), (1, 1e-5)):
        def at(x):
            r = d.evaluate(*((x, E) if k == 0 else (A, x)), guess=ev.orbit)
            return np.array([r.W_cb, r.max_mu])
        x0 = (A, E)[k]
        fd = (at(x0 + h) - at(x0 - h)) / (2 * h)
        impl = np.array([ev.grad_W_cb[k], ev.grad_max_mu[k]])
        print(f"d/d{('alpha_f', 'eta')[k]}: implicit {impl}, central differences {fd}")
        assert np.all(np.abs(impl - fd) <= 1e-4 * np.abs(fd))


def test_adjoint_matches_tangent(params, dense):
    d, ev = dense
    assert d.gradient_mode == "adjoint"
    t = FoilDesign(params, 0.3, linear_solver=DenseCondensation(), gradient_mode="tangent")
    assert t.gradient_mode == "tangent"
    et = t.evaluate(A, E, gradient=True, guess=ev.orbit)
    print("adjoint", ev.grad_W_cb, ev.grad_max_mu, "tangent", et.grad_W_cb, et.grad_max_mu)
    np.testing.assert_allclose(ev.grad_W_cb, et.grad_W_cb, rtol=1e-9)
    np.testing.assert_allclose(ev.grad_max_mu, et.grad_max_mu, rtol=1e-9)


def test_sparse_adjoint_matches_sparse_tangent(params, dense):
    _, ev = dense
    a = FoilDesign(params, 0.3, linear_solver=SparseSweep(), gradient_mode="adjoint").evaluate(A, E, gradient=True)
    t = FoilDesign(params, 0.3, linear_solver=SparseSweep(), gradient_mode="tangent").evaluate(A, E, gradient=True)
    np.testing.assert_allclose(a.grad_W_cb, t.grad_W_cb, rtol=1e-8)
    np.testing.assert_allclose(a.grad_max_mu, t.grad_max_mu, rtol=1e-7)


def test_bad_gradient_mode(params):
    with pytest.raises(ParameterError, match="gradient_mode"):
        FoilDesign(params, 0.3, gradient_mode="reverse")


def test_sparse_path_matches_dense(params, dense):
    _, ev = dense
    s = FoilDesign(params, 0.3, linear_solver=SparseSweep()).evaluate(A, E, gradient=True)
    assert abs(s.W_cb - ev.W_cb) < 1e-12
    assert abs(s.max_mu - ev.max_mu) < 1e-8  # sparse multipliers: linearisation of the last Newton iterate
    assert np.allclose(s.grad_W_cb, ev.grad_W_cb, rtol=1e-8)
    assert np.allclose(s.grad_max_mu, ev.grad_max_mu, rtol=1e-8)


def test_counts_and_bounds(params, dense):
    d, _ = dense
    n0, g0 = d.n_solves, d.n_gradients
    d.evaluate(0.2, 0.05)
    assert (d.n_solves, d.n_gradients) == (n0 + 1, g0)
    with pytest.raises(ParameterError, match="alpha_f"):
        d.evaluate(3.0, 0.05)
    with pytest.raises(ParameterError, match="eta"):
        d.evaluate(0.1, 0.0)
    assert d.n_solves == n0 + 1  # rejected before any solve


def test_max_mu_at_low_speed_is_flagged_where_the_mesh_does_not_resolve_it():
    """At Omega_bar 0.1 the period is long and the rotor mode goes through about a cycle per mesh interval: on
    the 16x2 grid N = 16 gives max|mu| = 0.283 (Gauss) where the cycle's is 0.247.  The independent reference:
    the orbit is small at this speed, so the rotor pair's multiplier is exp(lam T) of the static equilibrium's
    least damped eigenvalue.  The evaluation says so (``resolved`` False) at N = 16, and agrees at N = 64."""
    from gfbjax import cont
    from gfbjax.analyses.cycles import continue_gfb_equilibria

    omega = 0.1
    params = gfbjax.reference_system(Nx=16, Nz=2).nondim()
    eq = continue_gfb_equilibria(params, omega, omega + 0.05, cont.EquilibriumSettings(max_points=1))
    ev = eq.multipliers[0]
    reference = float(np.max(np.abs(np.exp(ev * 2 * np.pi / omega))))
    coarse = FoilDesign(params, omega, N=16).evaluate(float(params.alpha_f), float(params.eta))
    fine = FoilDesign(params, omega, N=64).evaluate(float(params.alpha_f), float(params.eta))
    assert not coarse.resolved and coarse.multiplier_error > 0.1 and abs(coarse.max_mu - reference) > 0.02
    assert fine.resolved and abs(fine.max_mu - reference) < 1e-3
