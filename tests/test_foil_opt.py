"""Foil optimisation (gfbjax.design.schedule) on a small grid (Nx=16, Nz=2).

The gradient-based optimiser (implicit gradients, projected quasi-Newton in log variables) must land on the
optimum that the derivative-free pattern search of the paper (Appendix A2) finds independently, with fewer
cycle solves.  (The vmapped map sweep of gfbjax.design.maps has no test here: its compiled kernel dead-locks XLA:CPU
intermittently, see gfbjax/design/maps.py.)
"""
from __future__ import annotations

import numpy as np
import pytest

import gfbjax
from gfbjax.cont import Outcome
from gfbjax.design.evaluate import FoilDesign
from gfbjax.design.schedule import optimize_at_speed, optimized_continuation
from gfbjax.params import ParameterError


@pytest.fixture(scope="module")
def smooth():
    # smoothed Gumbel condition: with the exact max() the multipliers jump where a node's pressure crosses ambient
    return gfbjax.reference_system(Nx=16, Nz=2, gumbel_width=1e-3).nondim()


def test_gradient_optimum_matches_pattern_search(smooth):
    d = FoilDesign(smooth, 0.4, N=8)
    start = d.evaluate(0.1, 0.05).orbit
    g = optimize_at_speed(d, "max_mu", "gradient", (0.1, 0.05))
    d.set_speed(0.4, start)
    p = optimize_at_speed(d, "max_mu", "pattern", (0.1, 0.05), mesh_tol=1e-4)
    print(f"gradient: {g.alpha_f:.6g} {g.eta:.6g} {g.value:.10f} ({g.n_solves} solves, {g.reason}); "
          f"pattern: {p.alpha_f:.6g} {p.eta:.6g} {p.value:.10f} ({p.n_solves} solves, {p.reason})")
    assert g.reason == "kkt"
    assert g.value <= p.value + 1e-7           # as good as the pattern search's optimum (to its mesh)
    assert abs(g.eta - p.eta) < 1e-3 * p.eta and abs(g.alpha_f - p.alpha_f) < 1e-3 * p.alpha_f
    assert g.n_solves * 3 < p.n_solves
    assert g.evaluation.stable


def test_optimized_continuation_records_and_stops(smooth):
    s = optimized_continuation(smooth, 0.3, 0.4, 0.05, objective="max_mu", N=8)
    assert s.omega == pytest.approx([0.3, 0.35, 0.4])
    assert all(s.stable) and s.bifurcation_free_to == pytest.approx(0.4)
    assert s.outcome is Outcome.REACHED_END, s.message
    assert len(s.alpha_f) == len(s.W_cb) == len(s.multipliers) == 3
    # each optimum carries the mesh's resolution of its multipliers (README, "Fast and unresolved modes")
    assert len(s.multiplier_error) == 3 and all(np.isfinite(s.multiplier_error))
    assert s.to_dict()["max_mu_resolved"] == [e <= 1e-3 for e in s.multiplier_error]
    with pytest.raises(ParameterError, match="d_omega"):
        optimized_continuation(smooth, 0.3, 0.4, 0.0)
