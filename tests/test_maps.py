"""Energy maps over the foil properties (gfbjax.design.maps) on a small system (Nx=16, Nz=2, N=8): the batched
(vmapped) sweep against the point-by-point loop over the same dense Newton corrector from the same start, and the
stepped map (every foil reached from a solved neighbour) against both.

The 3 x 3 grids span the foil bounds, so they hold foils that converge from the reference foil's cycle and foils
that do not (measured: 6 of 9 at Omega_bar 0.4 under the corrected preset, 4 of 9 at 0.2 under the paper preset;
the paper preset's own foil has no cycle at 0.4).  The batch must agree with the loop on which, and on the works
where both converge (1e-9 relative: same start, same phase condition).  The stepped map must converge wherever
the batch does and at foils where it does not; where both converge they reach the same cycle along different
paths with the same phase reference, so they agree to the Newton tolerance (measured: 1e-14 relative; a phase
reference taken from each start instead gives differences up to 1e-4, the size of the discretisation error).
The batched step also exercises the XLA:CPU dead-lock fixed in collocation.condense (four concurrent batched
triangular solves): before that fix the first sweep hung.  Every energy_map sweep here has 9 members, so the
batched kernel compiles once.
"""
from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import gfbjax
from gfbjax.design.evaluate import CycleNotConverged, FoilDesign
from gfbjax.design.maps import energy_map, energy_map_loop, energy_map_stepped
from gfbjax.params import ParameterError

ALPHA = np.array([0.005, 0.1, 2.0])
ETA = np.array([1e-4, 0.03, 10.0])
# Under the paper preset the walks to alpha_f >= 0.45 at low eta stall on this 3 x 3 grid (on a 5 x 5 grid they
# get there: the film is closed), and the stalled walks would cost most of the test's time.
PAPER_ALPHA = np.array([0.005, 0.1, 0.2])
MESH = dict(N=8, m=3)  # the notebooks' coarse mesh


def system(preset: str):
    return gfbjax.reference_system(preset=preset, Nx=16, Nz=2).nondim()


@pytest.fixture(scope="module")
def maps():
    p = system("corrected")
    return energy_map(p, 0.4, ALPHA, ETA, **MESH), energy_map_loop(p, 0.4, ALPHA, ETA, **MESH)


def test_batch_agrees_with_loop(maps):
    b, lp = maps
    print("converged batch\n", b.converged, "\nloop\n", lp.converged, "\nW_cb\n", b.W_cb, "\n", lp.W_cb)
    assert b.W_cb.shape == (ETA.size, ALPHA.size)
    assert np.array_equal(b.converged, lp.converged)
    assert 3 <= b.converged.sum() < b.converged.size
    ok = b.converged
    for k in ("W_cb", "W_cf", "W_fu", "h_min"):
        np.testing.assert_allclose(getattr(b, k)[ok], getattr(lp, k)[ok], rtol=1e-9, err_msg=k)
        assert np.all(np.isnan(getattr(b, k)[~ok]))
    assert np.all(b.W_cf[ok] > 0)
    # The unbalance's work leaves through the dampers or the films (energy.py: exact on a collocation cycle).
    np.testing.assert_allclose(b.W_fu[ok], b.W_cf[ok] + b.W_cb[ok], rtol=1e-9)
    assert b.max_mu is None and lp.max_mu is None


def check_stepped_against_batch(st, b):
    print("converged stepped\n", st.converged, "\nbatch\n", b.converged, "\nW_cb\n", st.W_cb, "\n", b.W_cb)
    assert st.W_cb.shape == b.W_cb.shape == st.max_mu.shape
    assert np.all(st.converged[b.converged])
    assert np.any(st.converged & ~b.converged)
    both = b.converged
    for k in ("W_cb", "W_cf", "W_fu"):
        np.testing.assert_allclose(getattr(st, k)[both], getattr(b, k)[both], rtol=1e-8, err_msg=k)
    np.testing.assert_allclose(st.h_min[both], b.h_min[both], rtol=0, atol=1e-8)
    ok = st.converged
    np.testing.assert_array_equal(np.isfinite(st.W_cb), ok)
    np.testing.assert_array_equal(np.isfinite(st.max_mu), ok)
    assert np.all(st.max_mu[ok] > 0) and np.all(st.iterations[ok] >= 0)
    assert st.member_steps >= ok.sum()


def test_stepped_converges_where_batch_fails_corrected(maps):
    b, _ = maps
    st = energy_map_stepped(system("corrected"), 0.4, ALPHA, ETA, **MESH)
    check_stepped_against_batch(st, b)
    assert st.converged.all()


def test_stepped_converges_where_batch_fails_paper():
    p = system("paper")
    b = energy_map(p, 0.2, PAPER_ALPHA, ETA, **MESH)
    st = energy_map_stepped(p, 0.2, PAPER_ALPHA, ETA, **MESH)
    check_stepped_against_batch(st, b)
    assert st.converged.all()


def test_stepped_starts_elsewhere_when_the_own_foil_has_no_cycle():
    # Paper preset at Omega_bar 0.3: the unbalance ramp to the own foil's cycle stalls (measured), so energy_map
    # cannot start; the stepped map starts at the soft foil, whose own unbalance response has a cycle, and the walk
    # from there to alpha_f 0.1 stalls (measured: 38 Newton steps in all).
    p = system("paper")
    with pytest.raises(CycleNotConverged):
        energy_map(p, 0.3, [0.1, 2.0], [10.0], **MESH)
    st = energy_map_stepped(p, 0.3, [0.1, 2.0], [10.0], **MESH)
    print(st.converged, st.W_cb, st.member_steps)
    np.testing.assert_array_equal(st.converged, [[False, True]])
    direct = FoilDesign(eqx.tree_at(lambda q: (q.alpha_f, q.eta), p, (jnp.asarray(2.0), jnp.asarray(10.0))), 0.3,
                        **MESH).evaluate(2.0, 10.0)
    np.testing.assert_allclose(st.W_cb[0, 1], direct.W_cb, rtol=1e-9)
    np.testing.assert_allclose(st.max_mu[0, 1], direct.max_mu, rtol=1e-9)
    assert np.isnan(st.W_cb[0, 0]) and np.isnan(st.max_mu[0, 0])


@pytest.mark.parametrize("fn", [energy_map, energy_map_stepped])
def test_bad_grid_is_rejected_before_solving(fn):
    p = system("corrected")
    with pytest.raises(ParameterError, match="at least one value"):
        fn(p, 0.4, [], [0.1])
    with pytest.raises(ParameterError, match="alpha_f"):
        fn(p, 0.4, [0.001, 0.1], [0.1])
    with pytest.raises(ParameterError, match="alpha_f"):
        fn(p, 0.4, [-0.1], [0.1])
    with pytest.raises(ParameterError, match="eta"):
        fn(p, 0.4, [0.1], [20.0])
    with pytest.raises(ParameterError, match="eta"):
        fn(p, 0.4, [0.1], [np.nan])


@pytest.mark.parametrize("kw, match", [(dict(tries=0), "tries"), (dict(tries=1.5), "tries"),
                                       (dict(min_step=0.0), "min_step"), (dict(min_step=2.0), "min_step")])
def test_stepped_rejects_bad_walk_settings(kw, match):
    with pytest.raises(ParameterError, match=match):
        energy_map_stepped(system("corrected"), 0.4, [0.1], [0.1], **kw)
