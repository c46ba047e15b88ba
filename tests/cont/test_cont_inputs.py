"""Inputs that do not fit together are refused before any work, with the field named; a numerical failure of the
linear algebra ends a branch with its points kept; a bug in user code propagates."""
import jax.numpy as jnp
import numpy as np
import pytest

import gfbjax.cont._floquet as floquet_module
from gfbjax.cont import (Arnoldi, BlockKrylov, CycleProblem, CycleSettings, EquilibriumProblem, EquilibriumSettings,
                         LinearSolveError, Natural, Outcome, SparseSweep, continue_cycles, continue_equilibria,
                         correct_cycle, hopf_point, start_from_function, start_from_hopf)
from cont_systems import stuart_landau

W = 2.0


def _sl_start(st, n=2):
    return start_from_function(lambda t: np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)]
                                                  + [0 * t] * (n - 2), 1) * np.r_[[0.7] * 2, [0.0] * (n - 2)],
                               np.pi, 0.5, st)


def test_start_orbit_and_f_must_fit_the_problem():
    st = CycleSettings(m=3, N=6, max_points=2)
    with pytest.raises(ValueError, match="start orbit has 2 states but problem.n = 3"):
        continue_cycles(CycleProblem(stuart_landau, 3, jnp.asarray(W)), st, _sl_start(st))
    three = lambda x, lam, a: jnp.concatenate([x, x[:1]])  # noqa: E731 - returns n + 1 values
    with pytest.raises(ValueError, match=r"returned shape \(3,\).*must return \(2,\)"):
        continue_cycles(CycleProblem(three, 2), st, _sl_start(st))
    with pytest.raises(ValueError, match=r"returned shape"):
        continue_equilibria(EquilibriumProblem(three, 2), EquilibriumSettings(), np.zeros(2), 0.0)
    with pytest.raises(ValueError, match="settings must be CycleSettings"):
        continue_cycles(CycleProblem(stuart_landau, 2, jnp.asarray(W)), EquilibriumSettings(), _sl_start(st))


def test_floquet_method_must_see_past_the_trivial_multiplier():
    """Arnoldi with k = 1 would return only the trivial multiplier and call any cycle stable."""
    pattern = np.ones((2, 2), bool)
    st = CycleSettings(m=3, N=6, max_points=2, floquet=Arnoldi(k=1))
    with pytest.raises(ValueError, match="Arnoldi"):
        continue_cycles(CycleProblem(stuart_landau, 2, jnp.asarray(W), jac_sparsity=pattern), st, _sl_start(st))
    st = CycleSettings(m=3, N=6, max_points=2, floquet=BlockKrylov(k=1))
    with pytest.raises(ValueError, match="BlockKrylov"):
        continue_cycles(CycleProblem(stuart_landau, 2, jnp.asarray(W), jac_sparsity=pattern), st, _sl_start(st))
    st = CycleSettings(m=3, N=6, max_points=2, linear_solver=SparseSweep())  # n = 2: the default gets n - 2 = 0
    with pytest.raises(ValueError, match="BlockKrylov.*caps it whatever k is"):  # no advice to raise k
        continue_cycles(CycleProblem(stuart_landau, 2, jnp.asarray(W), jac_sparsity=pattern), st, _sl_start(st))


def test_memory_is_checked_before_work():
    """n = 40, m = 7, N = 20000 with the dense solver would need ~75 GiB: refused at once."""
    n = 40
    prob = CycleProblem(lambda x, lam, a: jnp.concatenate([stuart_landau(x[:2], lam, a), -x[2:]]), n, jnp.asarray(W))
    st = CycleSettings(m=7, N=20_000, max_points=2)
    start = start_from_function(lambda t: np.concatenate([np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)], 1),
                                                          np.zeros((len(t), n - 2))], 1), np.pi, 0.5, st)
    with pytest.raises(ValueError, match="N = 20000 mesh intervals.*GiB"):
        continue_cycles(prob, st, start)
    with pytest.raises(ValueError, match="N = 20000 mesh intervals"):
        correct_cycle(prob, start.orbit, settings=st)


def test_natural_parameter_cannot_leave_a_bifurcation_point():
    prob = EquilibriumProblem(stuart_landau, 2, jnp.asarray(W))
    hp = hopf_point(prob, continue_equilibria(prob, EquilibriumSettings(ds=0.07, max_points=8), np.zeros(2), -0.3))
    st = CycleSettings(m=3, N=6, max_points=2, algorithm=Natural())
    with pytest.raises(ValueError, match="PseudoArclength"):
        continue_cycles(CycleProblem(stuart_landau, 2, jnp.asarray(W)), st, start_from_hopf(hp, st))


def test_linear_algebra_failure_ends_the_branch_and_keeps_the_points(monkeypatch):
    """ARPACK failing on the 4th point: the branch ends with LINEAR_SOLVE_FAILED and its 3 points."""
    n = 6
    prob = CycleProblem(lambda x, lam, a: jnp.concatenate([stuart_landau(x[:2], lam, a), -x[2:]]), n,
                        jnp.asarray(W), jac_sparsity=np.ones((n, n), bool))
    st = CycleSettings(m=3, N=6, ds=0.05, max_points=10, linear_solver=SparseSweep(), floquet=Arnoldi(k=3))
    calls = {"n": 0}
    real = Arnoldi.multipliers

    def flaky(self, lin, memo):
        calls["n"] += 1
        if calls["n"] == 4:
            raise LinearSolveError("Arnoldi (ARPACK) did not converge (simulated)")
        return real(self, lin, memo)

    monkeypatch.setattr(floquet_module.Arnoldi, "multipliers", flaky)
    br = continue_cycles(prob, st, _sl_start(st, n))
    assert br.outcome is Outcome.LINEAR_SOLVE_FAILED and "simulated" in br.message
    assert len(br) == 3


def test_speed_settings_are_checked():
    """Review cases: tol_inside and the predictor switches were accepted whatever their value."""
    from gfbjax.cont import PseudoArclength
    for bad in (-1.0, 0.0, float("nan"), 2.0):
        with pytest.raises(ValueError, match="tol_inside"):
            BlockKrylov(tol_inside=bad)
    for bad in ("no", None, 1):
        with pytest.raises(ValueError, match="quadratic"):
            PseudoArclength(quadratic=bad)
        with pytest.raises(ValueError, match="secant"):
            PseudoArclength(secant=bad)
    with pytest.raises(ValueError, match="chord"):
        SparseSweep(chord=1.5)
    with pytest.raises(ValueError, match="gmres_forcing"):
        SparseSweep(gmres_forcing=0.0)
