"""Two faults met while running the paper's literal conventions (issue 13), each pinned by a test.

(i)  An optimiser whose optimum lies on a design bound returned ``eta = exp(log(10)) = 10.000000000000002``, which the
     bound check of the cycle evaluation refused (``gfbjax optimize`` exited 2).
(ii) With the literal unbalance (24.1 um carried by the disc, eps = 1.26) the optimised continuation could not
     start at Omega_bar = 0.1: the linear forced response used as the first guess sweeps the journal through the
     foil (negative film), and Newton diverged from it.  The start now ramps the unbalance up.
"""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

import gfbjax
from gfbjax.design.evaluate import FOIL_BOUNDS, check_foil
from gfbjax.design.optimizers import minimize_log_box
from gfbjax.params import ParameterError

TINY = dict(Nx=16, Nz=2)


# -- (i) optimiser output on a bound -------------------------------------------------------------------------

def test_log_box_optimum_on_upper_bound_is_the_bound():
    lo, hi = np.array([0.005, 1e-4]), np.array([2.0, 10.0])
    assert np.exp(np.log(10.0)) > 10.0  # the rounding that caused the fault

    def fg(x):  # minimum at alpha_f = 0.3, eta pushed against its upper bound 10
        f = (math.log(x[0]) - math.log(0.3)) ** 2 - math.log(x[1])
        return f, np.array([2 * (math.log(x[0]) - math.log(0.3)) / x[0], -1.0 / x[1]])

    res = minimize_log_box(fg, np.array([0.1, 0.05]), lo, hi)
    assert res.reason == "kkt"
    assert res.x[1] == 10.0 and res.x[0] == pytest.approx(0.3, rel=1e-5)
    for h in res.history:  # every point handed to the objective is inside the box, bounds included
        assert np.all(h.x >= lo) and np.all(h.x <= hi), h.x
    assert check_foil(*res.x) == (pytest.approx(0.3, rel=1e-5), 10.0)


def test_check_foil_snaps_rounding_only():
    (a_lo, a_hi), (e_lo, e_hi) = FOIL_BOUNDS["alpha_f"], FOIL_BOUNDS["eta"]
    below, above = (lambda v: np.nextafter(np.nextafter(v, 0.0), 0.0)), (lambda v: np.nextafter(v, np.inf))
    assert check_foil(below(a_lo), np.exp(np.log(e_hi))) == (a_lo, e_hi)
    assert check_foil(above(a_hi), below(e_lo)) == (a_hi, e_lo)
    assert check_foil(0.1, 1.0) == (0.1, 1.0)
    for bad in (e_hi * (1 + 1e-9), 10.5, float("nan")):
        with pytest.raises(ParameterError, match="eta"):
            check_foil(0.1, bad)
    with pytest.raises(ParameterError, match="alpha_f"):
        check_foil(a_lo * (1 - 1e-9), 1.0)


def test_optimize_at_speed_accepts_an_optimum_on_the_bound():
    """The whole loop of optimize_at_speed with a stand-in design whose evaluate() checks the bounds as the real
    one does (check_foil) and whose objective wants eta as large as allowed."""
    from gfbjax.design.schedule import optimize_at_speed

    class Design:
        params = SimpleNamespace(alpha_f=0.1, eta=0.05)
        omega, n_solves, n_gradients, orbit = 0.3, 0, 0, None

        def evaluate(self, alpha_f, eta, gradient=False):
            alpha_f, eta = check_foil(alpha_f, eta)
            self.n_solves += 1
            self.n_gradients += gradient
            mu = 0.5 + (math.log(alpha_f) - math.log(0.2)) ** 2 - 0.01 * math.log(eta)
            grad = np.array([2 * (math.log(alpha_f) - math.log(0.2)) / alpha_f, -0.01 / eta])
            return SimpleNamespace(alpha_f=alpha_f, eta=eta, W_cb=1.0, max_mu=mu, grad_max_mu=grad,
                                   grad_W_cb=-grad, orbit=None, stable=True)

    opt = optimize_at_speed(Design(), "max_mu", "gradient", (0.1, 0.05))
    assert opt.eta == 10.0 and opt.alpha_f == pytest.approx(0.2, rel=1e-4)


# -- (ii) start of the literal-unbalance cycle -----------------------------------------------------------------

@pytest.fixture(scope="module")
def paper_params():
    return gfbjax.reference_system(preset="paper", **TINY).nondim()


def test_literal_unbalance_start_ramps_and_converges(paper_params):
    from gfbjax import cont
    from gfbjax.analyses.cycles import (_guess_films, default_cycle_settings, gfb_cycle_problem,
                                        linear_response_start, unbalance_response_start)

    settings = default_cycle_settings(N=8, m=3)
    x_of_t, T, eq = linear_response_start(paper_params, 0.1)
    h_eq, dh = _guess_films(paper_params, x_of_t, np.asarray(eq.state))
    assert float(np.min(h_eq + dh)) < 0.0  # the premise: the linear guess closes the film at Omega_bar 0.1
    orbit, how = unbalance_response_start(paper_params, 0.1, settings)
    assert how == "unbalance ramp"
    assert float(orbit.lam) == 0.1 and float(orbit.T) == pytest.approx(2 * math.pi / 0.1, rel=1e-4)  # collocation error of the oscillator
    # the returned cycle solves the full-unbalance problem: a fresh Newton correction does not move it
    sol, _ = cont.correct_cycle(gfb_cycle_problem(paper_params), orbit, settings=settings)
    assert sol.converged and int(sol.iterations) <= 1
    assert float(np.max(np.abs(np.asarray(sol.x.xm) - np.asarray(orbit.xm)))) < 1e-7
    # and its film stays open
    from gfbjax.model import film
    import jax
    import jax.numpy as jnp

    h = np.asarray(jax.vmap(lambda x: film(x[:-2], paper_params))(jnp.asarray(orbit.xm)))
    assert h.min() > 0.0
    # the reference (corrected) unbalance keeps the plain linear start
    ref = gfbjax.reference_system(**TINY).nondim()
    assert unbalance_response_start(ref, 0.1, settings)[1] == "linear"


def test_optimized_continuation_starts_at_0p1_with_literal_unbalance(paper_params):
    from gfbjax.cont import Outcome
    from gfbjax.design.schedule import optimized_continuation

    s = optimized_continuation(paper_params, 0.1, 0.12, 0.02, objective="max_mu", method="pattern", N=8, m=3,
                               max_evals=2)
    assert s.outcome is not Outcome.NO_SOLUTION, s.message
    assert s.omega[:1] == [0.1]
    # the second speed is reached too (from 0.1 the warm start fails; the halved steps get there)
    assert s.omega == pytest.approx([0.1, 0.12]) or s.outcome is Outcome.UNSTABLE
