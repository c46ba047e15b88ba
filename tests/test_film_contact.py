"""Film contact on the GFB (trust issue, case k): with the paper's literal unbalance the film closes on the cycle
branch; the branch must end at the located contact (or flag the points), never continue silently."""
import numpy as np
import pytest

import gfbjax
from gfbjax.analyses.cycles import continue_gfb_cycles, default_cycle_settings, film_monitor
from gfbjax.analyses.static import solve_equilibrium
from gfbjax.cont import Outcome
from gfbjax.model.system import film
from gfbjax.params import ParameterError


@pytest.mark.slow
def test_literal_unbalance_branch_ends_at_contact():
    spec = gfbjax.reference_system(Nx=16, Nz=2).with_preset("paper")
    params = spec.nondim().traced()
    st = default_cycle_settings(m=4, N=8, max_points=20)
    br = continue_gfb_cycles(params, 0.2, 0.3, st, spec=spec)
    assert br.outcome is Outcome.CONTACT, br.message
    assert abs(br.monitor[-1]) < 1e-7 and np.all(br.monitor[:-1] > 0)
    assert br.lam[-1] < 0.3 and "h_min" in br.message
    assert br.monitor_info["name"] == "h_min" and br.monitor_info["minimum"] == 0.0


def test_monitor_is_the_film_minimum_at_equilibrium():
    """On an equilibrium the monitor is min_theta h(theta): at the static equilibrium of the reference system it
    equals the StaticResult's h_min, computed by the static solver's own path."""
    spec = gfbjax.reference_system(Nx=16, Nz=2)
    params = spec.nondim().traced()
    eq = solve_equilibrium(params, 0.3)
    mon = film_monitor()
    assert float(mon.fn(eq.state, 0.3, params)) == pytest.approx(eq.h_min, rel=1e-12)
    assert float(np.min(np.asarray(film(eq.state, params)))) == pytest.approx(eq.h_min, rel=1e-12)
    assert 0.0 < eq.h_min < 1.0


@pytest.mark.parametrize("kw, word", [({"h_rub": -2.0}, "h_rub"), ({"h_rub": 1.0}, "h_rub"),
                                      ({"on_contact": "ignore"}, "on_contact")])
def test_bad_contact_settings(kw, word):
    with pytest.raises(ParameterError, match=word):
        film_monitor(**kw)
