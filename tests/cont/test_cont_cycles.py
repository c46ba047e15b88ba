"""Cycle continuation: Hopf switching (super/subcritical), radius sqrt(lam),
fold of cycles, branch storage, settings validation."""
import json

import jax.numpy as jnp
import numpy as np
import pytest

from gfbjax.cont import (Branch, CycleProblem, CycleSettings, EquilibriumProblem, EquilibriumSettings, Natural,
                         Outcome, TransferProduct, continue_cycles, continue_equilibria, hopf_point,
                         start_from_branch, start_from_hopf)
from cont_systems import stuart_landau, stuart_landau_sub

W = 2.0


def _hopf(field):
    prob = EquilibriumProblem(field, 2, jnp.asarray(W))
    br = continue_equilibria(prob, EquilibriumSettings(ds=0.07, max_points=8), np.zeros(2), -0.3)
    return hopf_point(prob, br)


@pytest.fixture(scope="module")
def sl_branch():
    st = CycleSettings(m=4, N=10, ds=0.05, ds_max=0.2, max_points=12, lam_max=1.0, save_states=True)
    prob = CycleProblem(stuart_landau, 2, jnp.asarray(W))
    return continue_cycles(prob, st, start_from_hopf(_hopf(stuart_landau), st))


def test_supercritical_hopf_branch(sl_branch):
    br = sl_branch
    assert len(br) >= 6, br.message
    assert np.all(br.lam > 0)                                   # supercritical: lam > 0
    assert np.allclose(br.l2, np.sqrt(br.lam), rtol=1e-9)       # radius sqrt(lam)
    assert np.allclose(br.period, np.pi, rtol=1e-8)             # 2 pi / w
    # max over the collocation nodes (sampled, <= true max)
    assert np.all(br.xmax[:, 0] <= np.sqrt(br.lam) * (1 + 1e-12))
    assert np.allclose(br.xmax[:, 0], np.sqrt(br.lam), rtol=1e-3)
    assert np.max(br.trivial_error) < 1e-10
    assert np.allclose(br.multipliers[:, 1].real, np.exp(-2 * br.lam * np.pi), atol=1e-8)
    assert np.all(br.stable)
    assert br.outcome in (Outcome.REACHED_END, Outcome.MAX_POINTS)
    assert br.special == []


def test_save_load_roundtrip_plain_numpy(sl_branch, tmp_path):
    npz, js = sl_branch.save(tmp_path / "sl")
    with np.load(npz) as z:                      # plain numpy + json, no gfbjax
        assert np.array_equal(z["lam"], sl_branch.lam)
        assert np.array_equal(z["multipliers"], sl_branch.multipliers)
        assert z["state_xm"].shape == (len(sl_branch), 11, 2)
    meta = json.loads(js.read_text())
    assert meta["kind"] == "cycles" and meta["outcome"] == sl_branch.outcome.value and "lam" in meta["keys"]
    back = Branch.load(tmp_path / "sl")
    for k in ("lam", "period", "l2", "xmax", "xmin", "multipliers", "stable", "newton_iterations", "ds"):
        assert np.array_equal(getattr(back, k), getattr(sl_branch, k)), k
    assert back.outcome is sl_branch.outcome and back.message == sl_branch.message and back.m == 4
    assert meta["format"] == "gfbjax.cont.Branch" and meta["points"] == len(sl_branch) and back.meta == {}


def test_save_load_keeps_description(sl_branch, tmp_path):
    """meta, component names and units travel in the JSON sidecar; the engine itself writes no meta."""
    import dataclasses

    br = dataclasses.replace(sl_branch, component_names=["x", "y"], units={"lam": "1"},
                             meta={"system": "Stuart-Landau", "w": W, "nested": {"a": [1, 2]}})
    br.save(tmp_path / "d")
    back = Branch.load(tmp_path / "d.json")
    assert back.meta == br.meta and back.component_names == ["x", "y"] and back.units == {"lam": "1"}


def test_restart_from_saved_point(sl_branch):
    st = CycleSettings(m=4, N=10, ds=0.05, max_points=3, direction=-1)
    prob = CycleProblem(stuart_landau, 2, jnp.asarray(W))
    br = continue_cycles(prob, st, start_from_branch(sl_branch, 4))
    assert len(br) == 3 and br.lam[0] == pytest.approx(sl_branch.lam[4], abs=1e-12)
    assert br.lam[2] < br.lam[1] < br.lam[0]                    # direction=-1 honoured
    assert np.allclose(br.l2, np.sqrt(br.lam), rtol=1e-9)


def test_natural_parameter_mode():
    st = CycleSettings(m=4, N=10, ds=0.1, max_points=4, algorithm=Natural())
    prob = CycleProblem(stuart_landau, 2, jnp.asarray(W))
    from gfbjax.cont import start_from_function
    start = start_from_function(lambda t: 0.6 * np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)], 1),
                                np.pi, 0.3, st)
    br = continue_cycles(prob, st, start)
    assert np.allclose(np.diff(br.lam), 0.1, atol=1e-10)
    assert np.allclose(br.l2, np.sqrt(br.lam), rtol=1e-9)


def test_subcritical_hopf_and_fold_of_cycles():
    """r' = r (lam + r^2 - r^4): the branch leaves the Hopf point towards lam < 0
    (unstable cycles), turns at the fold of cycles r^2 = 1/2, lam = -1/4, and
    comes back as stable cycles."""
    st = CycleSettings(m=4, N=10, ds=0.05, ds_max=0.1, max_points=25, lam_max=0.2)
    prob = CycleProblem(stuart_landau_sub, 2, jnp.asarray(W))
    br = continue_cycles(prob, st, start_from_hopf(_hopf(stuart_landau_sub), st))
    assert br.lam[0] < 0 and not br.stable[0]
    r2 = br.l2 ** 2
    assert np.allclose(br.lam, r2 ** 2 - r2, atol=1e-9)
    lpc = br.special_of("LPC")
    assert len(lpc) == 1 and lpc[0].located, br.special
    assert abs(lpc[0].lam + 0.25) < 1e-8 and abs(lpc[0].residual) <= st.locate_tol
    assert br.stable[-1] and br.lam[-1] > -0.25


def test_bad_settings_name_the_field():
    with pytest.raises(ValueError, match="ds_min"):
        CycleSettings(ds=0.1, ds_min=0.5)
    with pytest.raises(ValueError, match="m "):
        CycleSettings(m=9)
    with pytest.raises(ValueError, match="algorithm"):
        CycleSettings(algorithm="shooting")
    with pytest.raises(ValueError, match="linear_solver"):
        CycleSettings(linear_solver="dense")
    with pytest.raises(ValueError, match="floquet"):
        CycleSettings(floquet="product")
    with pytest.raises(ValueError, match="n_trivial"):
        CycleProblem(stuart_landau, 2, n_trivial=3)


def test_neimark_sacker_detection_and_angle():
    from gfbjax.cont import start_from_function
    from cont_systems import torus_field
    nu = 0.7
    T = 2 * np.pi / W
    st = CycleSettings(m=4, N=10, ds=0.1, ds_max=0.2, max_points=20, lam_max=0.8, detect=("NS", "PD", "LPC"))
    prob = CycleProblem(torus_field, 4, jnp.asarray([W, nu]))
    start = start_from_function(
        lambda t: np.stack([np.sqrt(0.3) * np.cos(2 * np.pi * t), np.sqrt(0.3) * np.sin(2 * np.pi * t),
                            0 * t, 0 * t], 1), T, 0.3, st)
    br = continue_cycles(prob, st, start)
    ns = br.special_of("NS")
    assert len(ns) == 1 and ns[0].located, br.special
    assert abs(ns[0].lam - 0.5) < 1e-8
    assert abs(ns[0].angle - nu * T) < 1e-8
    assert br.stable[0] and not br.stable[-1]


def test_continuation_compiles_newton_kernel_once(sl_branch):
    """The Newton kernel is traced once per (f, n, N, m): lam, T, references are
    traced arrays.  Another continuation with the same shapes adds no entry."""
    from gfbjax.cont import _linear
    before = _linear._dense_correct._cache_size()
    st = CycleSettings(m=4, N=10, ds=0.05, max_points=3)
    prob = CycleProblem(stuart_landau, 2, jnp.asarray(W))
    continue_cycles(prob, st, start_from_branch(sl_branch, 2))
    assert _linear._dense_correct._cache_size() == before


def test_fixed_lam_and_arclength_rows_share_one_kernel(sl_branch):
    """Session 16: the fixed-lam row (natural_constraint) held Python zeros, weakly typed scalars to JAX, and every
    kernel that sees a constraint compiled once more for it than for the arclength row (the GFB's NS relocation
    recompiled the residual, 0.4 s).  Scalars of orbits and rows are stored strongly typed: one kernel serves
    both rows, and an orbit made from Python numbers."""
    import jax
    from gfbjax.cont import _collocation as col, _linear, bind_solver, natural_constraint, palc_constraint

    def field(x, lam, w):  # a vector field of its own: the kernels' caches start empty for it
        return stuart_landau(x, lam, w)

    prob = CycleProblem(field, 2, jnp.asarray(W))
    st = CycleSettings(m=4, N=10)
    o = start_from_branch(sl_branch, 2).orbit
    solver = bind_solver(prob, col.Scheme(4), st)
    before = _linear._dense_correct._cache_size()
    rows = [natural_constraint(o, float(o.lam)),
            palc_constraint(o, col.Orbit(o.mesh, 0 * o.xm, 0 * o.xi, 0.0, 1.0), 0.0),
            palc_constraint(o, col.Orbit(o.mesh, 0 * o.xm, 0 * o.xi, jnp.asarray(0.0), jnp.asarray(1.0)),
                            jnp.asarray(0.0))]
    for con in rows:
        assert not any(jax.typeof(leaf).weak_type for leaf in jax.tree_util.tree_leaves(con))
        sol, _ = solver.correct(o, con, st.newton)
        assert sol.converged
    assert _linear._dense_correct._cache_size() == before + 1
    # a period given as a weak integer array (jnp.asarray(3)), a 0-d NumPy integer (as np.load gives it) or another
    # precision is a float period, as the Python int 3 is: the corrector's loop, which carries floats, takes it
    for T in (3, jnp.asarray(3), np.array(3), jnp.int32(3), jnp.float32(3.0)):
        o3 = col.Orbit(o.mesh, o.xm, o.xi, T, o.lam)
        assert o3.T.dtype == o.T.dtype and not jax.typeof(o3.T).weak_type
        sol, _ = solver.correct(o3, natural_constraint(o3, float(o.lam)), st.newton)
        assert sol.converged and float(sol.x.T) == pytest.approx(float(o.T), rel=1e-6)
    # states given as float32 arrays or nested lists, and a mesh given as a list, are the computation's floats too
    for conv in (lambda a: np.asarray(a, np.float32), lambda a: jnp.asarray(a, jnp.float32),
                 lambda a: np.asarray(a).tolist()):
        o4 = col.Orbit(np.asarray(o.mesh).tolist(), conv(o.xm), conv(o.xi), o.T, o.lam)
        assert all(a.dtype == o.xm.dtype for a in (o4.mesh, o4.xm, o4.xi))
        sol, _ = solver.correct(o4, natural_constraint(o4, float(o.lam)), st.newton)
        assert sol.converged and float(sol.x.T) == pytest.approx(float(o.T), rel=1e-5)


def test_callback_stop_and_user_errors_propagate(sl_branch):
    prob = CycleProblem(stuart_landau, 2, jnp.asarray(W))
    st = CycleSettings(m=4, N=10, ds=0.05, max_points=10, floquet=TransferProduct())
    seen = []
    br = continue_cycles(prob, st, start_from_branch(sl_branch, 3),
                         callback=lambda i, rec: seen.append(i) or len(seen) < 3)
    assert br.outcome is Outcome.STOPPED and len(br) == 3 and seen == [0, 1, 2]
    assert np.allclose(br.l2, np.sqrt(br.lam), rtol=1e-9)

    def boom(i, rec):
        if i == 2:
            raise RuntimeError("model blew up")

    # a bug in user code is not a reason for the branch to end: it propagates
    with pytest.raises(RuntimeError, match="model blew up"):
        continue_cycles(prob, st, start_from_branch(sl_branch, 3), callback=boom, progress=True)

    def bad_field(x, lam, args):
        raise ValueError("shape mismatch in my field")

    with pytest.raises(ValueError, match="shape mismatch"):
        continue_cycles(CycleProblem(bad_field, 2, jnp.asarray(W)), st, start_from_branch(sl_branch, 3))


def bautin_radial(x, lam, w):
    """r' = r (lam + 2 r^2 - r^4), theta' = w in the plane: cycles r^2 = 1 +- sqrt(1 + lam), a fold of cycles at
    (lam, r) = (-1, 1), stable outside (r > 1), unstable inside."""
    r2 = x[0] ** 2 + x[1] ** 2
    g = lam + 2.0 * r2 - r2 ** 2
    return jnp.array([g * x[0] - w * x[1], w * x[0] + g * x[1]])


@pytest.mark.parametrize("direction", [1, -1])
def test_cycle_branch_starts_at_a_fold(direction):
    """Trust case f for cycles: started from the fold's orbit (r = 1) at lam = -1.0005, where no cycle exists and
    fixing lam cannot converge, the start is corrected along the null tangent onto the fold and the branch leaves
    it: one direction gives the stable half r > 1, the other the unstable half r < 1, both on r^4 - 2 r^2 = lam
    (closed form).  Before, the start failed (START_FAILED)."""
    from gfbjax.cont import start_from_function
    w = 1.0
    st = CycleSettings(m=4, N=20, ds=0.05, ds_max=0.1, max_points=8, direction=direction, save_states=True)
    prob = CycleProblem(bautin_radial, 2, jnp.asarray(w))
    start = start_from_function(lambda t: np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)], 1),
                                2 * np.pi / w, -1.0005, st)
    br = continue_cycles(prob, st, start)
    assert len(br) == 8, br.message
    xm = np.asarray(br.states["xm"])  # (points, N + 1, 2) mesh values: on a circle of radius r
    r = np.sqrt(np.mean(xm[..., 0] ** 2 + xm[..., 1] ** 2, axis=1))
    np.testing.assert_allclose(br.lam, r ** 4 - 2 * r ** 2, atol=1e-8)
    np.testing.assert_allclose(br.period, 2 * np.pi / w, rtol=1e-9)
    # the start is the fold itself: it may be reported as a located LPC there (a row at lam = -1), nothing else
    assert all(sp.type == "LPC" and sp.located and abs(sp.lam + 1.0) < 1e-8 for sp in br.special)
    away = np.abs(br.lam + 1.0) > 1e-6
    assert abs(br.lam[0] + 1.0) < 1e-6 and away.sum() >= 5
    sides = np.sign(r[away] - 1.0)
    assert np.all(sides == sides[0])
    assert np.all(br.stable[away] == (sides[0] > 0))


@pytest.mark.parametrize("ds, ds_max, dlam_max", [(0.05, 0.1, np.inf), (10.0, 20.0, 0.05)])
def test_start_without_a_solution_nearby_fails_instead_of_moving(ds, ds_max, dlam_max):
    """Asked to start at lam = -1.5, where the radial equation has no cycle and no fold is near (the fold is at -1),
    the start fails; before, the correction along the null tangent ran off to lam = -0.28 and the branch was
    returned as if it started there.  Also with a large arclength step and a small dlam_max (as on the GFB, whose
    arclength holds the period): the move of 1.2 in lam was compared with ds = 10 and let through."""
    from gfbjax.cont import Outcome, start_from_function
    st = CycleSettings(m=4, N=20, ds=ds, ds_max=ds_max, dlam_max=dlam_max, max_points=8)
    prob = CycleProblem(bautin_radial, 2, jnp.asarray(1.0))
    start = start_from_function(lambda t: np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)], 1),
                                2 * np.pi, -1.5, st)
    br = continue_cycles(prob, st, start)
    assert br.outcome is Outcome.START_FAILED and len(br) == 0, br.message
    assert "farther than" in br.message or "did not converge" in br.message


def test_a_family_followed_down_to_its_hopf_point_ends_there(tmp_path):
    """Supercritical Stuart-Landau from lam = 0.5 towards smaller lam: the cycles (radius sqrt(lam)) shrink to the
    equilibrium at the Hopf point lam = 0, where the family ends.  A new user's audit: the discrete family ran on
    through zero amplitude and back along itself, and the turn was reported as a located LPC at lam = 1e-15 (there
    is no fold of cycles).  Now the branch ends there with a HOPF as its last row, also when resumed."""
    from gfbjax.cont import start_from_function

    prob = CycleProblem(stuart_landau, 2, jnp.asarray(W))
    for ds_max in (0.3, 0.1):
        st = CycleSettings(m=4, N=10, ds=0.05, ds_max=ds_max, max_points=30, lam_min=-0.5, lam_max=0.6, direction=-1)
        r0 = np.sqrt(0.5)
        start = start_from_function(lambda t: r0 * np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)], 1),
                                    2 * np.pi / W, 0.5, st)
        br = continue_cycles(prob, st, start, checkpoint=tmp_path / str(ds_max))
        assert br.outcome is Outcome.ENDED_AT_HOPF, br.message
        assert [s.type for s in br.special] == ["HOPF"], br.special
        hopf = br.special[0]
        # located, or bracketed where the fold test jumps at zero amplitude: its error bar covers lam = 0
        assert np.isfinite(hopf.residual) and abs(hopf.lam) <= max(hopf.lam_error, 1e-9)
        assert hopf.index == len(br) - 1
        np.testing.assert_allclose(hopf.omega, W, rtol=1e-6)
        np.testing.assert_allclose(br.l2[:-1] ** 2, 0.0 + br.lam[:-1], rtol=1e-6, atol=1e-9)  # |x|^2 = lam
        assert np.all(np.diff(br.lam) < 0)  # never back up along the family
        again = continue_cycles(prob, st, start, checkpoint=tmp_path / str(ds_max))
        assert again.outcome is Outcome.ENDED_AT_HOPF and len(again) == len(br)
        assert [(s.type, s.index) for s in again.special] == [(s.type, s.index) for s in br.special]


@pytest.mark.parametrize("ds_max, q0", [(0.1, 0.3), (0.05, 0.2), (0.2, 0.4)])
def test_a_subcritical_family_followed_up_to_its_hopf_point_ends_there(ds_max, q0):
    """Subcritical Stuart-Landau (cycles at lam = r^4 - r^2), started on the small unstable cycles (r^2 = q0) and
    followed towards the Hopf point lam = 0 (a reviewer's case): the fold test jumps there, so the point is only
    bracketed at some step sizes; it ran back through zero amplitude and the fold at lam = -1/4 (and reported a
    BPC).  The family ends at its Hopf point at every step size."""
    from gfbjax.cont import start_from_function

    prob = CycleProblem(stuart_landau_sub, 2, jnp.asarray(1.0))
    st = CycleSettings(m=4, N=10, ds=0.05, ds_max=ds_max, max_points=40, lam_min=-0.5, lam_max=0.6, direction=1)
    r0 = np.sqrt(q0)
    start = start_from_function(lambda t: r0 * np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)], 1),
                                2 * np.pi, q0 * q0 - q0, st)
    br = continue_cycles(prob, st, start)
    assert br.outcome is Outcome.ENDED_AT_HOPF, br.message
    assert [s.type for s in br.special] == ["HOPF"] and abs(br.special[0].lam) < 1e-6, br.special
    assert np.all(np.diff(br.lam) > 0)


def test_an_interrupted_end_at_a_hopf_point_resumes_to_the_same_end(tmp_path):
    """Interrupted by the callback at its last row (the Hopf point) after that step was written, and resumed: the
    same branch, not one stepping on past the end (a reviewer's case: the step carried no end marker)."""
    from gfbjax.cont import start_from_function

    prob = CycleProblem(stuart_landau, 2, jnp.asarray(1.3))
    st = CycleSettings(m=4, N=10, ds=0.05, ds_max=0.2, max_points=30, lam_min=-0.5, lam_max=1.0, direction=-1)
    r0 = np.sqrt(0.5)
    start = start_from_function(lambda t: r0 * np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)], 1),
                                2 * np.pi / 1.3, 0.5, st)
    _resumes_to_the_same_end(prob, st, start, tmp_path, Outcome.ENDED_AT_HOPF)


def _resumes_to_the_same_end(prob, st, start, tmp_path, outcome):
    """A branch that ends with ``outcome``, stopped by the callback at its last row (after that step was written)
    and resumed from the checkpoint: the same end, rows and special points."""
    ref = continue_cycles(prob, st, start)
    assert ref.outcome is outcome, ref.message
    last = len(ref) - 1

    def stop_at_the_end(i, rec):
        if i >= last:
            raise KeyboardInterrupt

    cut = continue_cycles(prob, st, start, checkpoint=tmp_path, callback=stop_at_the_end)
    assert cut.outcome is Outcome.INTERRUPTED and len(cut) == len(ref)
    again = continue_cycles(prob, st, start, checkpoint=tmp_path)
    assert again.outcome is outcome and len(again) == len(ref), (again.message, len(again))
    assert [(s.type, s.index, s.lam) for s in again.special] == [(s.type, s.index, s.lam) for s in ref.special]
    np.testing.assert_allclose(again.lam, ref.lam, rtol=0, atol=1e-12)


def _at_zero(end):
    """A family's end at lam = 0 (the analytic value): located there, or bracketed by an error bar that covers 0
    and is small (1e-3: a few of the last, halved steps), with its estimate well inside the bar (lam = L + c a^2
    through the last two cycles, or the two sides of the end, is exact to O(a^4): the bar is the step's span)."""
    if end.located:
        assert abs(end.lam) < 1e-6, end
    else:
        assert abs(end.lam) <= end.lam_error < 1e-3, end
        assert abs(end.lam) <= max(0.05 * end.lam_error, 1e-9), end


def _scaled_sub(scale):
    """The subcritical Stuart-Landau field in states scaled by ``scale`` (cycles of radius scale * r, r^2 = q on
    lam = q^2 - q): the same dynamics at another size of the states."""
    def field(x, lam, w):
        return scale * stuart_landau_sub(x / scale, lam, w)
    return field


@pytest.mark.parametrize("scale", [0.03, 0.01, 0.001])
def test_a_small_subcritical_family_ends_at_its_hopf_point_instead_of_sliding_onto_the_equilibrium(scale):
    """The subcritical case above with states of size 0.03 and below (a reviewer's case): the step past the Hopf
    point lam = 0 converged on the equilibrium, a constant orbit (amplitude 1e-17, then 1e-126), which solves the
    collocation equations with any period, and the branch crept on along it for 35 points with no event and no
    warning.  Every row but the last is a cycle of the family, and the branch ends at its Hopf point: located, or
    bracketed with an error bar that covers lam = 0."""
    from gfbjax.cont import start_from_function

    prob = CycleProblem(_scaled_sub(scale), 2, jnp.asarray(1.0))
    st = CycleSettings(m=4, N=10, ds=0.05, ds_max=0.1, max_points=40, lam_min=-0.5, lam_max=0.6, direction=1)
    r0 = scale * np.sqrt(0.3)
    start = start_from_function(lambda t: r0 * np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)], 1),
                                2 * np.pi, 0.3 ** 2 - 0.3, st)
    br = continue_cycles(prob, st, start)
    assert br.outcome is Outcome.ENDED_AT_HOPF, br.message
    q = (br.l2[:-1] / scale) ** 2
    np.testing.assert_allclose(br.lam[:-1], q ** 2 - q, rtol=0, atol=1e-9)
    assert np.all(q > 1e-8) and np.all(np.diff(br.lam) > 0)
    [hopf] = br.special
    assert hopf.type == "HOPF" and hopf.index == len(br) - 1
    _at_zero(hopf)
    assert abs(hopf.period - 2 * np.pi) < 1e-6


def test_a_correction_that_lands_on_the_equilibrium_finds_no_cycle():
    """correct_cycle with a pseudo-arclength constraint whose step passes the Hopf point of the small subcritical
    family: Newton converges to the constant orbit (the constraint's period term makes that system regular), which
    is no cycle: NO_SOLUTION.  A shorter step converges on the family (lam = q^2 - q)."""
    from gfbjax.cont import Scheme, correct_cycle, orbit_from_function, palc_constraint, uniform_mesh
    from gfbjax.cont import _collocation as col

    scale, scheme = 0.03, Scheme(4)
    prob = CycleProblem(_scaled_sub(scale), 2, jnp.asarray(1.0))

    def circle(q):
        r = scale * np.sqrt(q)
        return orbit_from_function(lambda t: r * np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)], 1),
                                   2 * np.pi, q * q - q, scheme, uniform_mesh(10))

    base = circle(0.04)
    d = col.add(base, col.scaled(circle(0.06), -1.0))
    tau = col.scaled(d, 1.0 / float(jnp.sqrt(col.inner(d, d, scheme) + d.T ** 2 + d.lam ** 2)))
    outcomes = {}
    for ds in (0.02, 0.04):
        guess = col.add(base, col.scaled(tau, ds))
        sol, lin = correct_cycle(prob, guess, palc_constraint(base, tau, ds, base), settings=CycleSettings(m=4, N=10))
        outcomes[ds] = sol.outcome
        if ds == 0.02:
            q = float(col.l2_norm(sol.x, scheme) / scale) ** 2
            assert sol.converged and abs(float(sol.x.lam) - (q * q - q)) < 1e-9
    assert outcomes[0.04] is Outcome.NO_SOLUTION and lin is None, outcomes


def _pd_branches(sat):
    """cont_systems.pd_family (w = 2 pi, mu = 0.5): the period-1 cycles across the PD at lam = 0, and the doubled
    family switched onto there, followed to |lam| = 0.3."""
    from cont_systems import pd_family
    from gfbjax.cont import start_from_function, start_from_pd

    prob = CycleProblem(pd_family, 4, jnp.asarray([2 * np.pi, 0.5, sat]))
    st = CycleSettings(m=4, N=12, ds=0.05, ds_max=0.1, max_points=20, lam_min=-0.3, lam_max=0.3, save_states=True)
    start = start_from_function(lambda t: np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t), 0 * t, 0 * t], 1),
                                1.0, -0.3, st)
    single = continue_cycles(prob, st, start)
    st2 = CycleSettings(m=4, N=24, ds=0.02, ds_max=0.05, max_points=30, lam_min=-0.3, lam_max=0.3,
                        save_states=True)
    return prob, continue_cycles(prob, st2, start_from_pd(prob, single, 0, st2))


@pytest.mark.parametrize("sat", [1.0, -1.0, 1e4])
def test_a_period_doubled_family_followed_back_ends_at_its_pd_point(sat):
    """The doubled family of pd_family (|z| = sqrt(lam / sat), period 2), followed back from |lam| = 0.3 to the PD
    point at lam = 0 (a reviewer's class: families that shrink onto what they were born from).  It used to report
    a fold of cycles (LPC) and a branch point (BPC) there and run back along itself (the same cycles shifted by a
    period), or, with small z (sat = 1e4), slide on along the period-1 cycle traversed twice, reported as
    period-doubled cycles, to the end of the range with no event.  It ends at the PD point: located, or bracketed
    with an error bar that covers lam = 0; every row before it is a doubled cycle of the family."""
    from gfbjax.cont import start_from_branch

    prob, doubled = _pd_branches(sat)
    assert doubled.outcome is Outcome.REACHED_END and not doubled.special, (doubled.message, doubled.special)
    st = CycleSettings(m=4, N=24, ds=0.02, ds_max=0.05, max_points=40, lam_min=-0.3, lam_max=0.3,
                       direction=-int(np.sign(sat)))
    br = continue_cycles(prob, st, start_from_branch(doubled, -1))
    assert br.outcome is Outcome.ENDED_AT_PD, br.message
    [pd] = br.special
    assert pd.type == "PD" and pd.index == len(br) - 1, br.special
    _at_zero(pd)
    z_pp = (br.xmax - br.xmin)[:-1, 2]
    np.testing.assert_allclose(z_pp, 2 * np.sqrt(br.lam[:-1] / sat), rtol=1e-3)
    np.testing.assert_allclose(br.period, 2.0, rtol=1e-9)
    assert np.all(np.diff(br.lam) * np.sign(sat) < 0)


def _doubled_guess(s0, extra=0):
    """A doubled cycle of the pd_family kind (period 2: the oscillator turns twice, z once) with |z|^2 = s0."""
    return lambda t: np.stack([np.cos(4 * np.pi * t), np.sin(4 * np.pi * t), np.sqrt(s0) * np.cos(2 * np.pi * t),
                               np.sqrt(s0) * np.sin(2 * np.pi * t)] + [0 * t] * extra, 1)


def _drive(x, w=2 * np.pi, mu=0.5):
    """The oscillator and z-rotation of cont_systems.pd_family with the gain left out: (u', v', z-part(g))."""
    u, v, z1, z2 = x[0], x[1], x[2], x[3]
    r2, rot = u * u + v * v, 0.5 * w
    return (jnp.stack([u - w * v - u * r2, w * u + v - v * r2]),
            lambda g: jnp.stack([(g + mu * u) * z1 + (mu * v - rot) * z2, (mu * v + rot) * z1 + (g - mu * u) * z2]))


@pytest.mark.parametrize("a", [0.01, 0.03])
def test_a_fold_next_to_the_hopf_end_is_passed_before_the_family_ends(a):
    """r' = r (lam + a r^2 - r^4): a fold of cycles at r^2 = a/2, lam = -a^2/4, close to the family's end at the
    Hopf point lam = 0 (a new user's audit).  With ds_max = 0.2 one step crossed the fold, zero amplitude and the
    fold's mirror image (r -> -r, the same cycles): the fold test changed sign twice, the fold's multiplier through
    +1 was read as a BPC, and the branch ran back over itself to lam_max.  Both are found now, in order."""
    from gfbjax.cont import start_from_function

    def field(x, lam, w):
        r2 = x[0] ** 2 + x[1] ** 2
        g = lam + a * r2 - r2 ** 2
        return jnp.array([g * x[0] - w * x[1], w * x[0] + g * x[1]])

    st = CycleSettings(m=4, N=10, ds=0.05, ds_max=0.2, max_points=80, lam_min=-0.5, lam_max=1.0, direction=-1)
    r0 = np.sqrt(0.6)
    start = start_from_function(lambda t: r0 * np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)], 1),
                                2 * np.pi, 0.36 - 0.6 * a, st)
    br = continue_cycles(CycleProblem(field, 2, jnp.asarray(1.0)), st, start)
    assert br.outcome is Outcome.ENDED_AT_HOPF, br.message
    assert [s.type for s in br.special] == ["LPC", "HOPF"], br.special
    lpc, hopf = br.special
    assert lpc.located and abs(lpc.lam + a * a / 4) < 1e-9
    _at_zero(hopf)
    q = br.l2[:-1] ** 2
    np.testing.assert_allclose(br.lam[:-1], q * q - a * q, rtol=0, atol=1e-9)


@pytest.mark.parametrize("a", [0.01, 0.03])
def test_a_fold_next_to_the_pd_end_is_passed_before_the_family_ends(a):
    """The doubled family of pd_family with gain lam - mu + a s - s^2 (s = |z|^2): doubled cycles on
    lam = s^2 - a s, a fold at s = a/2, lam = -a^2/4, next to the end at the PD point lam = 0 (the same audit:
    a spurious BPC, and the branch ran back over itself)."""
    from gfbjax.cont import start_from_function

    def field(x, lam, args):
        osc, zdot = _drive(x)
        s = x[2] ** 2 + x[3] ** 2
        return jnp.concatenate([osc, zdot(lam - 0.5 + a * s - s * s)])

    st = CycleSettings(m=4, N=24, ds=0.05, ds_max=0.2, max_points=80, lam_min=-0.5, lam_max=0.5, direction=-1)
    br = continue_cycles(CycleProblem(field, 4, jnp.asarray(0.0)), st,
                         start_from_function(_doubled_guess(0.6), 2.0, 0.36 - 0.6 * a, st))
    assert br.outcome is Outcome.ENDED_AT_PD, br.message
    assert [s.type for s in br.special] == ["LPC", "PD"], br.special
    lpc, pd = br.special
    assert lpc.located and abs(lpc.lam + a * a / 4) < 1e-9
    _at_zero(pd)
    s = ((br.xmax - br.xmin)[:-1, 2] / 2) ** 2
    np.testing.assert_allclose(br.lam[:-1], s * s - a * s, rtol=0, atol=1e-6)  # s read at the nodes (<= the max)


@pytest.mark.parametrize("lb, ds_max", [(1e-3, 0.2), (1e-6, 0.2), (1e-4, 0.05)])
def test_a_branch_point_next_to_the_pd_end_is_reported(lb, ds_max):
    """pd_family (sat = 1) with a fifth state y' = (lam - lb) y - y^3: a pitchfork of the doubled cycles (a BPC) at
    lam = lb, close to the family's end at the PD point lam = 0 (the same audit: the last step ran through both,
    the BPC test changed sign twice, and only the end was reported)."""
    from gfbjax.cont import start_from_function

    def field(x, lam, args):
        osc, zdot = _drive(x)
        s = x[2] ** 2 + x[3] ** 2
        return jnp.concatenate([osc, zdot(lam - 0.5 - s), jnp.stack([(lam - lb) * x[4] - x[4] ** 3])])

    st = CycleSettings(m=4, N=24, ds=0.05, ds_max=ds_max, max_points=80, lam_min=-0.5, lam_max=0.5, direction=-1)
    br = continue_cycles(CycleProblem(field, 5, jnp.asarray(0.0)), st,
                         start_from_function(_doubled_guess(0.3, extra=1), 2.0, 0.3, st))
    assert br.outcome is Outcome.ENDED_AT_PD, br.message
    assert [s.type for s in br.special] == ["BPC", "PD"], br.special
    bpc, pd = br.special
    assert bpc.located and abs(bpc.lam - lb) < 1e-9, bpc
    _at_zero(pd)


def test_a_distant_guess_that_converges_to_a_small_cycle_is_a_cycle():
    """Stuart-Landau at lam = 1e-7 from a guess of radius 1: Newton converges to the genuine cycle of radius
    sqrt(lam) = 3.2e-4, which a test against the guess alone (1e-3 of its amplitude) took for the equilibrium (the
    same audit).  A collapse must be the constant orbit itself, to the corrector's tolerance."""
    from gfbjax.cont import Scheme, correct_cycle, orbit_from_function, uniform_mesh
    from gfbjax.cont import _collocation as col

    scheme, lam = Scheme(4), 1e-7
    guess = orbit_from_function(lambda t: np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)], 1), 2 * np.pi,
                                lam, scheme, uniform_mesh(24))
    sol, lin = correct_cycle(CycleProblem(stuart_landau, 2, jnp.asarray(1.0)), guess,
                             settings=CycleSettings(m=4, N=24, newton_max_iter=80))
    assert sol.outcome is Outcome.CONVERGED and lin is not None, sol.outcome
    np.testing.assert_allclose(float(col.l2_norm(sol.x, scheme)), np.sqrt(lam), rtol=1e-6)


@pytest.mark.parametrize("N", [20, 37])
def test_the_first_step_from_a_hopf_point_is_not_halved(N):
    """From start_from_hopf the first point is the equilibrium, here at (1, 0.5), whose odd part under a
    half-period shift is interpolation noise (1e-16) on these meshes: its sign against the next point's decides
    nothing, but could be read as a step through the family's end and the first step halved six times (a
    reviewer's case).  The points are those of N = 16, where the noise is exactly 0, to the discretisation's
    difference."""
    def shifted(x, lam, w):
        return stuart_landau(x - jnp.array([1.0, 0.5]), lam, w)

    def run(n):
        st = CycleSettings(m=4, N=n, ds=0.05, ds_max=0.2, max_points=4, lam_max=1.0)
        prob = EquilibriumProblem(shifted, 2, jnp.asarray(W))
        eqs = continue_equilibria(prob, EquilibriumSettings(ds=0.07, max_points=8), np.array([1.0, 0.5]), -0.3)
        return continue_cycles(CycleProblem(shifted, 2, jnp.asarray(W)), st, start_from_hopf(hopf_point(prob, eqs),
                                                                                              st))
    np.testing.assert_allclose(run(N).lam, run(16).lam, rtol=1e-6)


def _sl_down(**kw):
    """Supercritical Stuart-Landau (w = 1.3, cycles r^2 = lam) followed down from lam = 0.5 to its Hopf point."""
    from gfbjax.cont import start_from_function

    st = CycleSettings(**{**dict(m=4, N=10, ds=0.05, ds_max=0.2, max_points=40, lam_min=-0.5, lam_max=1.0,
                                 direction=-1), **kw})
    r0 = np.sqrt(0.5)
    start = start_from_function(lambda t: r0 * np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)], 1),
                                2 * np.pi / 1.3, 0.5, st)
    return continue_cycles(CycleProblem(stuart_landau, 2, jnp.asarray(1.3)), st, start)


@pytest.mark.parametrize("kw", [dict(algorithm=Natural(), ds_max=0.1), dict(detect=("PD", "NS", "BPC")),
                                dict(detect=("PD", "NS"))])
def test_the_hopf_end_is_found_by_natural_steps_and_without_the_fold_test(kw):
    """The end at lam = 0 by natural-parameter steps (a correction at lam < 0 collapses onto the equilibrium) and
    with the fold test not among detect (the step passes through zero amplitude; nothing locates it, and the
    branch used to run back over itself): bracketed, with an error bar that covers 0 (a reviewer's cases)."""
    br = _sl_down(**kw)
    assert br.outcome is Outcome.ENDED_AT_HOPF, br.message
    [hopf] = br.special
    assert hopf.type == "HOPF" and hopf.index == len(br) - 1
    _at_zero(hopf)
    np.testing.assert_allclose(br.l2[:-1] ** 2, br.lam[:-1], rtol=1e-9)


def test_an_interrupted_end_at_a_pd_point_resumes_to_the_same_end(tmp_path):
    """As for the Hopf end: the doubled family of pd_family with small z (sat = 1e4, the collapse path), stopped at
    its last row and resumed from the checkpoint, ends at the same PD point with the same rows."""
    from gfbjax.cont import start_from_branch

    prob, doubled = _pd_branches(1e4)
    st = CycleSettings(m=4, N=24, ds=0.02, ds_max=0.05, max_points=40, lam_min=-0.3, lam_max=0.3, direction=-1)
    _resumes_to_the_same_end(prob, st, start_from_branch(doubled, -1), tmp_path, Outcome.ENDED_AT_PD)
