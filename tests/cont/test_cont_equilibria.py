"""Equilibrium continuation: fold of x' = lam - x^2, Hopf of Stuart-Landau."""
import jax.numpy as jnp
import numpy as np
import pytest

from gfbjax.cont import EquilibriumProblem, EquilibriumSettings, continue_equilibria, hopf_point
from cont_systems import fold_1d, stuart_landau


def test_fold_at_zero():
    """x' = lam - x^2: branch x = sqrt(lam) folds at (lam, x) = (0, 0)."""
    prob = EquilibriumProblem(fold_1d, 1)
    br = continue_equilibria(prob, EquilibriumSettings(ds=0.1, max_points=30, direction=-1), [1.0], 1.0)
    folds = br.special_of("FOLD")
    assert len(folds) == 1 and folds[0].located
    assert abs(folds[0].lam) < 1e-9
    i = folds[0].index
    assert abs(br.states["x"][i, 0]) < 1e-4
    # past the fold the lower branch x = -sqrt(lam) (unstable) is followed
    assert br.lam[-1] > 0 and br.states["x"][-1, 0] < 0 and not br.stable[-1]
    assert br.stable[0]
    assert np.allclose(br.states["x"][:, 0] ** 2, br.lam, atol=1e-9)


def test_hopf_stuart_landau():
    w = 2.0
    prob = EquilibriumProblem(stuart_landau, 2, jnp.asarray(w))
    br = continue_equilibria(prob, EquilibriumSettings(ds=0.07, max_points=8), np.zeros(2), -0.3)
    hs = br.special_of("HOPF")
    assert len(hs) == 1
    assert abs(hs[0].lam) < 1e-10 and abs(hs[0].omega - w) < 1e-10
    hp = hopf_point(prob, br)
    assert abs(hp.omega - w) < 1e-10 and abs(hp.lam) < 1e-10
    J = np.array([[hp.lam, -w], [w, hp.lam]])
    assert np.allclose(J @ hp.v, 1j * hp.omega * hp.v, atol=1e-10)


def test_bad_settings_name_the_field():
    with pytest.raises(ValueError, match="ds_min"):
        EquilibriumSettings(ds=0.1, ds_min=0.2)
    with pytest.raises(ValueError, match="detect"):
        EquilibriumSettings(detect=("HOPF", "PD"))
