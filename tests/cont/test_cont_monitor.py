"""Physical validity monitors (trust issue, item 6): a branch that crosses its bound ends there, with the crossing
located as its last point (outcome CONTACT), or goes on with those points flagged; never silently."""
import jax.numpy as jnp
import numpy as np
import pytest

from gfbjax.cont import (Branch, CycleProblem, CycleSettings, EquilibriumProblem, EquilibriumSettings, Monitor,
                         Outcome, continue_cycles, continue_equilibria, hopf_point, start_from_hopf)
from cont_systems import stuart_landau

W = 2.0


def linear(x, p, args):
    return jnp.array([p - x[0]])  # equilibria x = p


def test_equilibria_end_on_the_bound():
    mon = Monitor("gap", lambda x, p, a: 1.0 - x[0], 0.0)
    br = continue_equilibria(EquilibriumProblem(linear, 1, monitor=mon), EquilibriumSettings(ds=0.3, lam_max=3.0),
                             np.array([0.0]), 0.0)
    assert br.outcome is Outcome.CONTACT, br.message
    assert br.lam[-1] == pytest.approx(1.0, abs=1e-9)  # the crossing x = 1 located, recorded last
    assert np.all(br.monitor[:-1] > 0.0) and abs(br.monitor[-1]) < 1e-9
    assert "gap" in br.message


def test_flagging_monitor_goes_on(tmp_path):
    mon = Monitor("gap", lambda x, p, a: 1.0 - x[0], 0.0, stop=False, unit="m")
    br = continue_equilibria(EquilibriumProblem(linear, 1, monitor=mon), EquilibriumSettings(ds=0.3, lam_max=3.0),
                             np.array([0.0]), 0.0)
    assert br.outcome is Outcome.REACHED_END and br.lam[-1] == pytest.approx(3.0)
    np.testing.assert_array_equal(br.flagged, br.lam >= 1.0)
    np.testing.assert_allclose(br.monitor, 1.0 - br.lam, atol=1e-12)
    br.save(tmp_path / "b")
    back = Branch.load(tmp_path / "b")
    np.testing.assert_array_equal(back.monitor, br.monitor)
    assert back.monitor_info == {"name": "gap", "minimum": 0.0, "unit": "m", "stop": False}
    np.testing.assert_array_equal(back.flagged, br.flagged)
    assert "monitor" in br.to_xarray()


def test_cycles_end_where_the_orbit_reaches_the_bound():
    """Stuart-Landau cycles of radius sqrt(lam): the bound x_0 <= 0.5 is reached at lam = 1/4 (to the sampling of
    the orbit at its collocation nodes)."""
    eq = EquilibriumProblem(stuart_landau, 2, jnp.asarray(W))
    hp = hopf_point(eq, continue_equilibria(eq, EquilibriumSettings(ds=0.07, max_points=8), np.zeros(2), -0.3))
    mon = Monitor("clearance", lambda x, lam, a: 0.5 - x[0], 0.0)
    st = CycleSettings(m=4, N=10, ds=0.05, ds_max=0.2, max_points=30, lam_max=1.0)
    br = continue_cycles(CycleProblem(stuart_landau, 2, jnp.asarray(W), monitor=mon), st, start_from_hopf(hp, st))
    assert br.outcome is Outcome.CONTACT, br.message
    assert br.lam[-1] == pytest.approx(0.25, rel=1e-2) and br.lam[-1] >= 0.25 - 1e-9
    assert abs(br.monitor[-1]) < 1e-7 and np.all(br.monitor[:-1] > 0.0)
    np.testing.assert_allclose(0.5 - br.monitor, br.xmax[:, 0], atol=1e-12)  # the same node maximum


def test_bad_monitor_is_refused():
    with pytest.raises(ValueError, match="minimum"):
        Monitor("gap", lambda x, p, a: x[0], float("nan"))
    with pytest.raises(ValueError, match="monitor"):
        EquilibriumProblem(linear, 1, monitor=lambda x, p, a: x[0])


def test_the_row_at_a_stopping_bound_is_reported_and_kept(tmp_path):
    """x' = p - x with the monitor 1 - x >= 0: the branch ends at x = 1 with the located crossing as its last row.
    That row reached neither the callback nor the checkpoint (a reviewer's case): a finished branch read back from
    its folder was one row short."""
    mon = Monitor("gap", lambda x, p, a: 1.0 - x[0], 0.0)
    prob, st = EquilibriumProblem(lambda x, p, a: jnp.array([p - x[0]]), 1, monitor=mon), \
        EquilibriumSettings(ds=0.3, lam_max=3.0)
    seen = []
    br = continue_equilibria(prob, st, np.array([0.0]), 0.0, callback=lambda i, r: seen.append(i),
                             checkpoint=tmp_path)
    assert br.outcome is Outcome.CONTACT and abs(br.lam[-1] - 1.0) < 1e-9
    assert seen == list(range(len(br)))
    back = continue_equilibria(prob, st, np.array([0.0]), 0.0, checkpoint=tmp_path)
    assert back.outcome is Outcome.CONTACT and len(back) == len(br) and back.lam[-1] == br.lam[-1]
