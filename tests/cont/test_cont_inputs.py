"""Inputs that do not fit together are refused before any work, with the field named; a numerical failure of the
linear algebra ends a branch with its points kept; a bug in user code propagates."""
import dataclasses
from types import SimpleNamespace

import jax.numpy as jnp
import numpy as np
import pytest

import gfbjax.cont._floquet as floquet_module
from gfbjax.cont import (Arnoldi, BlockKrylov, CycleProblem, CycleSettings, EquilibriumProblem, EquilibriumSettings,
                         LinearSolveError, Natural, Outcome, SparseSweep, continue_cycles, continue_equilibria,
                         correct_cycle, hopf_point, start_from_branch, start_from_function, start_from_hopf,
                         start_from_pd)
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


def test_start_orbit_arrays_of_the_wrong_shape_or_kind_are_named():
    """A hand-made start whose arrays do not fit together (a new user's report: JAX failed inside a concatenation
    naming none of them), and one whose degree is not the settings' (it silently replaced settings.m)."""
    from gfbjax.cont import CycleStart
    from gfbjax.cont._collocation import Orbit

    st = CycleSettings(m=3, N=6, max_points=2)
    o = _sl_start(st).orbit
    prob = CycleProblem(stuart_landau, 2, jnp.asarray(W))
    cases = [(o.mesh, o.xm[:-1], o.xi, r"xm \(6, 2\)"), (o.mesh, o.xm, o.xi[:-1], r"xi \(5, 2, 2\)"),
             (o.mesh[:-1], o.xm, o.xi, r"mesh \(6,\)"), (o.mesh, o.xm, o.xi[:, 0], r"xi \(6, 2\)")]
    for mesh, xm, xi, shown in cases:
        with pytest.raises(ValueError, match=r"start orbit must have mesh \(N\+1,\), xm \(N\+1, n\).*" + shown):
            continue_cycles(prob, st, CycleStart(Orbit(mesh, xm, xi, o.T, o.lam)))
    with pytest.raises(ValueError, match="start orbit's xm must be a real array, got str"):
        continue_cycles(prob, st, CycleStart(Orbit(o.mesh, "abc", o.xi, o.T, o.lam)))
    with pytest.raises(ValueError, match="start orbit's xi must be a real array, got .* of dtype complex"):
        continue_cycles(prob, st, CycleStart(Orbit(o.mesh, o.xm, o.xi + 0j, o.T, o.lam)))
    with pytest.raises(ValueError, match=r"start orbit has m = 3 .* but settings.m = 4"):
        continue_cycles(prob, CycleSettings(m=4, N=6, max_points=2), CycleStart(o))



def test_a_constant_guess_is_refused_naming_why():
    """A new user's all-zero start orbit ended "start point did not converge (nonfinite)" with no reason: a
    constant orbit is an equilibrium with any period, and as its own phase reference it makes the phase condition
    vanish (Newton's matrix is singular).  A Hopf start (constant, with the first harmonic as tangent) is allowed."""
    from gfbjax.cont import CycleStart, correct_cycle, natural_constraint, start_from_hopf
    from gfbjax.cont._collocation import Orbit

    st = CycleSettings(m=3, N=6, max_points=2)
    o = _sl_start(st).orbit
    prob = CycleProblem(stuart_landau, 2, jnp.asarray(W))
    for c in (0.0, 0.3):
        flat = Orbit(o.mesh, 0 * o.xm + c, 0 * o.xi + c, o.T, o.lam)
        with pytest.raises(ValueError, match=r"start orbit \(a guess without a tangent\) is constant .*start_from_hopf"):
            continue_cycles(prob, st, CycleStart(flat))
        for con in (None, natural_constraint(o, o.lam)):
            with pytest.raises(ValueError, match=r"the orbit is constant"):
                correct_cycle(prob, flat, con, settings=st)
    hopf = SimpleNamespace(lam=0.0, x=np.zeros(2), omega=float(W), v=np.array([1.0, -1.0j]))
    assert len(continue_cycles(prob, st, start_from_hopf(hopf, st))) == 2


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


@pytest.mark.parametrize("cls, field, bad", [
    (EquilibriumSettings, "dlam_max", True), (CycleSettings, "dlam_max", np.True_),
    (EquilibriumSettings, "direction", 1.0), (CycleSettings, "direction", True), (CycleSettings, "direction", 0),
    (EquilibriumSettings, "detect", "HOPF"), (EquilibriumSettings, "detect", ("HOPF", "LPC")),
    (CycleSettings, "save_states", "yes"), (CycleSettings, "save_states", 1),
    (EquilibriumSettings, "locate", "no"), (CycleSettings, "grow", True),
    (EquilibriumSettings, "lam_min", float("nan")), (EquilibriumSettings, "lam_max", float("nan")),
    (CycleSettings, "lam_min", float("inf")), (CycleSettings, "max_points", 10.0),
    (CycleSettings, "N", 16.0), (EquilibriumSettings, "ds", float("nan")),
])
def test_every_settings_field_refuses_a_value_of_the_wrong_kind(cls, field, bad):
    """Fresh-user cases: booleans for numbers, floats for orientations, strings for flags and a bare string for
    the event list were accepted.  Each is refused at construction, naming the field."""
    with pytest.raises(ValueError, match=field):
        cls(**{field: bad})


def test_numpy_numbers_and_lists_are_welcome_and_stored_plainly():
    """NumPy scalars (the natural result of array arithmetic) are accepted everywhere an int or float is, and stored
    as Python numbers; a list of events becomes a tuple, so that settings stay hashable."""
    st = CycleSettings(N=np.int64(12), m=np.int32(3), grow=np.float64(1.2), ds=np.float32(0.25),
                       detect=["NS", "PD", "NS"], direction=np.int64(-1))
    assert (type(st.N), type(st.m), type(st.grow), type(st.direction)) == (int, int, float, int)
    assert st.detect == ("NS", "PD") and st.direction == -1 and st.ds == 0.25
    hash(st)
    prob = CycleProblem(stuart_landau, np.int64(2), jnp.asarray(W), n_trivial=np.int64(1))
    assert type(prob.n_trivial) is int and prob.n_trivial == 1
    with pytest.raises(ValueError, match="n_trivial"):
        CycleProblem(stuart_landau, 2, n_trivial=3)


def test_a_start_outside_the_bounds_or_not_finite_is_refused():
    """A start outside [lam_min, lam_max] used to be recorded and then the branch jumped to the bound (lam0 = 2,
    lam_max = 1 gave the points 2.0 and 1.0); NaN starts ended with START_FAILED without naming the argument."""
    line = EquilibriumProblem(lambda x, p, a: jnp.array([p - x[0]]), 1)
    with pytest.raises(ValueError, match=r"lam0 = 2 lies outside .*\[-inf, 1\]"):
        continue_equilibria(line, EquilibriumSettings(lam_max=1.0), np.array([2.0]), 2.0)
    with pytest.raises(ValueError, match=r"lam0 = -3 lies outside"):
        continue_equilibria(line, EquilibriumSettings(lam_min=-1.0, lam_max=1.0), np.array([-3.0]), -3.0)
    with pytest.raises(ValueError, match="lam0 must be a number"):
        continue_equilibria(line, EquilibriumSettings(), np.array([0.0]), float("nan"))
    with pytest.raises(ValueError, match=r"x0 must be finite.*\[1\] = nan"):
        continue_equilibria(EquilibriumProblem(stuart_landau, 2, jnp.asarray(W)), EquilibriumSettings(),
                            np.array([0.0, np.nan]), 0.0)
    # on the bound itself is inside
    assert len(continue_equilibria(line, EquilibriumSettings(lam_max=1.0, max_points=3), np.array([1.0]), 1.0)) >= 1
    st = CycleSettings(m=3, N=6, max_points=2, lam_max=0.2)
    with pytest.raises(ValueError, match=r"the start's lam = 0.5 lies outside"):
        continue_cycles(CycleProblem(stuart_landau, 2, jnp.asarray(W)), st, _sl_start(st))
    st = CycleSettings(m=3, N=6, max_points=2)
    start = _sl_start(st)
    bad = type(start)(start.orbit.__class__(start.orbit.mesh, start.orbit.xm.at[2, 1].set(jnp.nan), start.orbit.xi,
                                            start.orbit.T, start.orbit.lam), start.tangent, start.label)
    with pytest.raises(ValueError, match="start orbit's xm must be finite"):
        continue_cycles(CycleProblem(stuart_landau, 2, jnp.asarray(W)), st, bad)


def test_a_vector_field_that_returns_nan_is_refused_or_ends_the_branch_with_a_reason():
    """At the start it raised a bare LinAlgError from an SVD (the fold start's null tangent of a NaN Jacobian): now
    a ValueError naming the components, before any work.  Past the start, the branch ends with the points before
    it and the corrector's own outcome."""
    nan_field = EquilibriumProblem(lambda x, p, a: jnp.array([p - x[0], x[1]]) * jnp.array([1.0, jnp.nan]), 2)
    with pytest.raises(ValueError, match=r"NaN or inf at x0 \(lam = 0\), in components 1"):
        continue_equilibria(nan_field, EquilibriumSettings(), np.zeros(2), 0.0)
    st = CycleSettings(m=3, N=6, max_points=2)
    nan_cycle = CycleProblem(lambda x, lam, a: stuart_landau(x, lam, a) / 0.0 * x[0], 2, jnp.asarray(W))
    with pytest.raises(ValueError, match="NaN or inf at the start orbit's first node"):
        continue_cycles(nan_cycle, st, _sl_start(st))
    later = EquilibriumProblem(lambda x, p, a: jnp.where(p > 0.5, jnp.nan, 1.0) * jnp.array([p - x[0]]), 1)
    br = continue_equilibria(later, EquilibriumSettings(ds=0.1), np.array([0.0]), 0.0)
    assert br.outcome is Outcome.STEP_TOO_SMALL and "nonfinite" in br.message and br.lam.max() <= 0.5


def test_an_event_not_localised_reports_the_step_in_lam_as_its_error():
    """Review case: with locate off, the error of a Hopf point was the arclength step (0.86 in Omega_bar for a
    step of 0.021 on a GFB branch).  It is the change of lam over the step that holds the event."""
    prob = EquilibriumProblem(stuart_landau, 2, jnp.asarray(W))
    br = continue_equilibria(prob, EquilibriumSettings(ds=0.07, max_points=12, locate=False), np.zeros(2), -0.3)
    (h,) = br.special_of("HOPF")
    assert h.localisation == "not localised" and br.lam[h.index - 1] < 0.0 <= br.lam[h.index]
    assert h.lam_error == pytest.approx(br.lam[h.index] - br.lam[h.index - 1], rel=1e-12)


def test_flags_and_orientations_accept_zero_dimensional_arrays():
    st = EquilibriumSettings(direction=np.array(-1), locate=np.array(True), detect=[np.str_("HOPF")])
    assert st.direction == -1 and type(st.direction) is int and st.locate is True and st.detect == ("HOPF",)
    assert type(st.detect[0]) is str


# ---------------------------------------------------------------- starts and corrections from stored results
@pytest.fixture(scope="module")
def sl_equilibria():
    """Stuart-Landau equilibria through lam = 0: one located HOPF point."""
    prob = EquilibriumProblem(stuart_landau, 2, jnp.asarray(W))
    return prob, continue_equilibria(prob, EquilibriumSettings(ds=0.07, max_points=8), np.zeros(2), -0.3)


@pytest.fixture(scope="module")
def sl_cycles(sl_equilibria):
    """Three stored Stuart-Landau cycles (no PD point on them)."""
    st = CycleSettings(m=3, N=6, ds=0.05, max_points=3, save_states=True)
    prob = CycleProblem(stuart_landau, 2, jnp.asarray(W))
    br = continue_cycles(prob, st, start_from_hopf(hopf_point(*sl_equilibria), st))
    assert len(br) == 3, br.message
    return prob, br


def _with_pd(br, **kw):
    """``br`` with one PD point (its state that of point 1); ``kw`` overrides the record's fields."""
    from gfbjax.cont import SpecialPoint
    state = {k: (v[1] if v.ndim and v.shape[0] == len(br) else v) for k, v in br.states.items()}
    fields = {"type": "PD", "lam": float(br.lam[1]), "index": 1, "spectrum": br.multipliers[1], "located": True,
              "residual": 0.0, "period": float(br.period[1]), "state": 0, **kw}
    return dataclasses.replace(br, special=[SpecialPoint(**fields)], special_states=[state])


@pytest.mark.parametrize("which", [5, 1, -2, -7, 0.0, True, "0", None])
def test_hopf_point_refuses_an_index_past_its_hopf_points(sl_equilibria, which):
    """Review cases: 5, 1, -2, -7 and True (read as 1) raised a bare IndexError, 0.0, "0" and None a TypeError."""
    with pytest.raises(ValueError, match=r"which must be an int in \[-1, 0\] \(the branch has 1 HOPF point\)"):
        hopf_point(*sl_equilibria, which)


def test_hopf_point_accepts_numpy_and_negative_indices(sl_equilibria):
    first = hopf_point(*sl_equilibria)
    for which in (np.int64(0), -1, np.array(-1)):
        assert hopf_point(*sl_equilibria, which).lam == first.lam


def test_hopf_point_needs_the_equilibria_of_its_problem(sl_equilibria, sl_cycles):
    """A cycles branch said "no HOPF special point"; a problem of another size or kind was used as it came, and a
    HOPF record without its state raised a TypeError."""
    prob, br = sl_equilibria
    with pytest.raises(ValueError, match="branch must be a branch of equilibria.*'cycles'"):
        hopf_point(prob, sl_cycles[1])
    with pytest.raises(ValueError, match="problem must be an EquilibriumProblem, got CycleProblem"):
        hopf_point(sl_cycles[0], br)
    with pytest.raises(ValueError, match=r"problem.n = 3.*2 states"):
        hopf_point(EquilibriumProblem(stuart_landau, 3, jnp.asarray(W)), br)
    stateless = dataclasses.replace(br, special=[dataclasses.replace(s, state=None) for s in br.special])
    with pytest.raises(ValueError, match="HOPF point near lam = .* has no stored state"):
        hopf_point(prob, stateless)


@pytest.mark.parametrize("index", [3, -4, 10, 1.0, True, "0", None])
def test_start_from_branch_refuses_an_index_past_its_points(sl_cycles, index):
    """Review cases: 3, -4, 10, 1.0 and "0" raised a bare IndexError; True and None were taken as NumPy indices (a
    new axis), giving an orbit of the wrong shape."""
    with pytest.raises(ValueError, match=r"index must be an int in \[-3, 2\] \(the branch has 3 points\)"):
        start_from_branch(sl_cycles[1], index)


def test_start_from_branch_counts_negative_indices_from_the_end(sl_cycles):
    br = sl_cycles[1]
    last = start_from_branch(br, -1)
    assert float(last.orbit.lam) == br.lam[-1] and last.label == "branch[2]"
    assert float(start_from_branch(br, np.int64(1)).orbit.lam) == br.lam[1]


def test_start_from_branch_needs_a_branch_of_cycles(sl_equilibria):
    """Review case: a branch of equilibria (its states hold x only) raised KeyError: 'mesh'."""
    with pytest.raises(ValueError, match="branch must be a branch of cycles.*'equilibria'"):
        start_from_branch(sl_equilibria[1], 0)


@pytest.mark.parametrize("special, match", [
    (0, r"special = 0 cannot index the branch: it has no PD points"),
    (1.0, r"special must be an int index .* or a SpecialPoint, got 1.0"),
    (True, r"special must be an int index .* or a SpecialPoint, got True"),
])
def test_start_from_pd_refuses_a_pd_the_branch_does_not_have(sl_cycles, special, match):
    """Review cases: 0 and True (taken as 1) raised a bare IndexError, 1.0 an AttributeError."""
    with pytest.raises(ValueError, match=match):
        start_from_pd(sl_cycles[0], sl_cycles[1], special)


@pytest.mark.parametrize("special", [1, -2, 7])
def test_start_from_pd_names_how_many_pd_points_there_are(sl_cycles, special):
    """Review cases: a bare IndexError that did not say how many PD points there are."""
    with pytest.raises(ValueError, match=r"special must be an int in \[-1, 0\] \(the branch has 1 PD point\)"):
        start_from_pd(sl_cycles[0], _with_pd(sl_cycles[1]), special)


@pytest.mark.parametrize("fields, match", [
    ({"type": "NS", "angle": 1.0}, r"special must be a PD point, got a point of type 'NS'"),
    ({"located": False, "residual": float("nan")}, r"PD point near lam = .* was not located \(not localised\)"),
    ({"located": False, "residual": 0.3}, r"PD point near lam = .* was not located \(bracketed\)"),
    ({"state": None}, r"PD point near lam = .* has no stored state"),
    ({"state": 4}, r"PD point near lam = .* has no stored state"),
])
def test_start_from_pd_needs_a_located_pd_point_with_its_state(sl_cycles, fields, match):
    """Review cases: an NS point and an unlocated PD point were switched from as if they were located PD points;
    a record without its state raised a TypeError (None) or an IndexError (4)."""
    br = _with_pd(sl_cycles[1], **fields)
    with pytest.raises(ValueError, match=match):
        start_from_pd(sl_cycles[0], br, br.special[0])


def test_start_from_pd_refuses_a_point_of_another_branch(sl_cycles):
    """Review case: a PD point of branch B given with branch A was switched from at A's PD point (its state index
    read in A).  Index forms of the point are accepted: NumPy and 0-d array integers."""
    a = _with_pd(sl_cycles[1])
    b = _with_pd(sl_cycles[1], lam=float(sl_cycles[1].lam[2]))
    with pytest.raises(ValueError, match=r"special \(the PD point near lam = .*\) is not a special point of this "):
        start_from_pd(sl_cycles[0], a, b.special[0])
    assert start_from_pd(sl_cycles[0], a, a.special[0]).label == "PD switch"
    for index in (np.int64(0), np.array(0), jnp.asarray(0), -1):
        assert start_from_pd(sl_cycles[0], a, index).label == "PD switch"


def test_correct_cycle_refuses_a_constraint_of_another_mesh(sl_cycles):
    """Review case: a constraint built on an orbit of another N raised a JAX shape error from inside Newton."""
    from gfbjax.cont import natural_constraint
    st = CycleSettings(m=3, N=6)
    other = _sl_start(CycleSettings(m=3, N=8)).orbit
    with pytest.raises(ValueError, match=r"con was built on another mesh"):
        correct_cycle(sl_cycles[0], _sl_start(st).orbit, natural_constraint(other, 0.5), settings=st)


def test_start_from_pd_needs_the_problem_and_cycles_of_the_branch(sl_cycles, sl_equilibria):
    """A problem of another size or kind, a branch of equilibria and settings of the wrong kind are named before the
    transfer matrices are computed."""
    br = _with_pd(sl_cycles[1])
    big = CycleProblem(lambda x, lam, a: jnp.concatenate([stuart_landau(x[:2], lam, a), -x[2:]]), 4, jnp.asarray(W))
    with pytest.raises(ValueError, match=r"problem.n = 4.*2 states"):
        start_from_pd(big, br, 0)
    with pytest.raises(ValueError, match="problem must be a CycleProblem, got EquilibriumProblem"):
        start_from_pd(sl_equilibria[0], br, 0)
    with pytest.raises(ValueError, match="branch must be a branch of cycles.*'equilibria'"):
        start_from_pd(sl_cycles[0], sl_equilibria[1], 0)
    with pytest.raises(ValueError, match="settings must be CycleSettings or None"):
        start_from_pd(sl_cycles[0], br, 0, EquilibriumSettings())


@pytest.mark.parametrize("field, bad, match", [
    ("omega", 0.0, r"hopf.omega must be a number in \(0, inf\)"),
    ("omega", -2.0, r"hopf.omega must be a number in \(0, inf\)"),
    ("omega", float("nan"), r"hopf.omega must be a number"),
    ("omega", float("inf"), r"hopf.omega must be a number"),
    ("lam", float("nan"), r"hopf.lam must be a number"),
    ("x", np.array([0.0, np.nan]), r"hopf.x must be finite.*\[1\] = nan"),
    ("v", np.array([np.inf, 1j]), r"hopf.v must be finite.*\[0\] = \(?inf"),
    ("v", np.array([1.0, 1j, 0.0]), r"hopf.v must have the shape of hopf.x, \(2,\), got \(3,\)"),
    ("v", np.zeros(2, complex), r"hopf.v must not be zero"),
    ("x", np.zeros((1, 2)), r"hopf.x must be a vector"),
])
def test_start_from_hopf_refuses_a_hopf_point_that_is_not_one(sl_equilibria, field, bad, match):
    """Review cases: omega = 0 and v = 0 raised ZeroDivisionError; a negative, NaN or infinite omega, a NaN lam or
    state, a v of another length and a matrix x were accepted (a start of NaNs or of mismatched shapes, failing later
    without a reason)."""
    hp = dataclasses.replace(hopf_point(*sl_equilibria), **{field: bad})
    with pytest.raises(ValueError, match=match):
        start_from_hopf(hp, CycleSettings(m=3, N=6))


@pytest.mark.parametrize("entry", ["correct_cycle", "continue_cycles"])
def test_a_field_that_is_nan_at_a_later_node_is_refused_naming_the_node(entry):
    """Review case: f NaN on part of the orbit only (here where x1 < -0.5, t in about (0.63, 0.87)).  The start's
    first node is fine, so continue_cycles and correct_cycle handed it to Newton, which cannot say why it fails."""
    st = CycleSettings(m=3, N=6, max_points=2)
    part = CycleProblem(lambda x, lam, a: stuart_landau(x, lam, a) * jnp.where(x[1] < -0.5, jnp.nan, 1.0), 2,
                        jnp.asarray(W))
    what = "the start orbit" if entry == "continue_cycles" else "the orbit"
    with pytest.raises(ValueError, match=rf"NaN or inf at {what}'s point t = 0\.6479 \(in mesh interval \[mesh\[3\], "
                                         r"mesh\[4\]\] = \[0\.5, 0\.6667\]\), in components 0, 1, and at 8 more of its "
                                         r"37 points \(lam = 0\.5\)"):
        if entry == "continue_cycles":
            continue_cycles(part, st, _sl_start(st))
        else:
            correct_cycle(part, _sl_start(st).orbit, settings=st)


@pytest.mark.parametrize("arrays, match", [
    ({"xi": ("at", (3, 1, 0))}, r"the orbit's xi must be finite; it is NaN or inf at its node t = 0\.6111 \(in mesh "
                                r"interval \[mesh\[3\], mesh\[4\]\] = \[0\.5, 0\.6667\]\), in components 0$"),
    ({"xm": ("at", (2, 1))}, r"the orbit's xm must be finite; it is NaN or inf at its node t = 0\.3333 \(mesh\[2\]\), "
                             r"in components 1$"),
    ({"T": ("set", np.nan)}, r"the orbit's T \(period\) must be a number in \(0\.0, inf\)"),
    ({"T": ("set", 0.0)}, r"the orbit's T \(period\) must be a number in \(0\.0, inf\)"),
    ({"T": ("set", -2 * np.pi)}, r"the orbit's T \(period\) must be a number in \(0\.0, inf\)"),
    ({"lam": ("set", np.inf)}, r"the orbit's lam must be finite"),
    ({"mesh": ("set", np.linspace(0.0, 1.0, 7)[::-1])}, r"the orbit's mesh must increase strictly"),
])
def test_correct_cycle_refuses_an_orbit_that_is_not_finite(arrays, match):
    """Review cases: a NaN in the orbit, its period or parameter, or a reversed mesh went into Newton unchecked
    (continue_cycles checked them, correct_cycle did not)."""
    st = CycleSettings(m=3, N=6)
    orbit = _sl_start(st).orbit
    for name, (how, what) in arrays.items():
        value = getattr(orbit, name).at[what].set(np.nan) if how == "at" else jnp.asarray(what)
        orbit = dataclasses.replace(orbit, **{name: value})
    with pytest.raises(ValueError, match=match):
        correct_cycle(CycleProblem(stuart_landau, 2, jnp.asarray(W)), orbit, settings=st)
