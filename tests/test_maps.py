"""Batched (vmapped) energy maps (gfbjax.design.maps, gfbjax.cont.batched_newton) against the point-by-point loop over the same
dense Newton corrector from the same start, on a small grid (Nx=16, Nz=2, N=8, Omega_bar 0.4).

The batch and the loop agree to 1e-9 relative (same start, same phase condition).  The 3 x 2 grid spans the foil bounds, so it holds points that converge from the reference foil's cycle and points
that do not (measured: the extreme-compliance corner fails in both); the batch must agree with the loop on which,
and on W_cb and W_cf where both converge.  The batched step also exercises the XLA:CPU dead-lock fixed in
collocation.condense (four concurrent batched triangular solves): before that fix the first sweep hung.
"""
from __future__ import annotations

import numpy as np
import pytest

import gfbjax
from gfbjax.design.maps import energy_map, energy_map_loop
from gfbjax.params import ParameterError

ALPHA = np.array([0.005, 0.1, 2.0])
ETA = np.array([0.01, 1.0])


@pytest.fixture(scope="module")
def maps():
    p = gfbjax.reference_system(Nx=16, Nz=2).nondim()
    kw = dict(N=8)
    return energy_map(p, 0.4, ALPHA, ETA, **kw), energy_map_loop(p, 0.4, ALPHA, ETA, **kw)


def test_batch_agrees_with_loop(maps):
    b, lp = maps
    print("converged batch\n", b.converged, "\nloop\n", lp.converged, "\nW_cb\n", b.W_cb, "\n", lp.W_cb)
    assert b.W_cb.shape == (ETA.size, ALPHA.size)
    assert np.array_equal(b.converged, lp.converged)
    assert b.converged.sum() >= 3
    ok = b.converged
    np.testing.assert_allclose(b.W_cb[ok], lp.W_cb[ok], rtol=1e-9)
    np.testing.assert_allclose(b.W_cf[ok], lp.W_cf[ok], rtol=1e-9)
    assert np.all(np.isnan(b.W_cb[~ok]))
    assert np.all(b.W_cf[ok] > 0)


def test_bad_grid_is_rejected_before_solving():
    p = gfbjax.reference_system(Nx=16, Nz=2).nondim()
    with pytest.raises(ParameterError, match="alpha_f"):
        energy_map(p, 0.4, [0.001, 0.1], [0.1])
    with pytest.raises(ParameterError, match="eta"):
        energy_map(p, 0.4, [0.1], [20.0])
