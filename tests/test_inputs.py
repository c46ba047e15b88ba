"""Input checks in one place (gfbjax.limits): every range is a named Range, NumPy and concrete JAX numbers are
accepted, tracers are not checked, and each bad input found by trying the tool as a new user gets a one-line error
naming the field and its range before any long computation (issue 11, item 6)."""

from __future__ import annotations

import dataclasses
import math
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import gfbjax
from gfbjax import ParameterError, limits
from gfbjax.cli import main

SMALL = ["--nx", "16", "--nz", "2"]


def _run(argv, capsys):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def _one_error_line(err: str) -> str:
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("gfbjax: warning:")]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


@pytest.fixture
def small_params():
    return gfbjax.SystemSpec(Nx=16, Nz=2).nondim()


@pytest.fixture
def no_static_solve(monkeypatch):
    """Fail the test if a command gets as far as a static solve (the first computation of static and runup)."""
    import gfbjax.analyses.static as static

    def boom(*a, **k):
        raise AssertionError("computation started before the inputs were checked")

    monkeypatch.setattr(static, "solve_equilibrium", boom)
    return boom


# -- the Range type -----------------------------------------------------------------------------------------------


def test_range_message_names_field_value_and_range():
    with pytest.raises(ParameterError) as e:
        limits.SPEED.check(60.0)
    assert str(e.value).startswith("omega_bar = 60 is outside the allowed range (0, 50]")
    with pytest.raises(ParameterError, match=r"^--speed = 0 is outside the allowed range \(0, 50\]"):
        limits.SPEED.check(0, "--speed")
    with pytest.raises(ParameterError, match=r"R = -1 m is outside the allowed range \(0, 10\] m"):
        limits.R.check(-1.0)
    # a value just outside is not printed as the bound itself
    with pytest.raises(ParameterError, match=r"50\.0000001"):
        limits.SPEED.check(50.0000001)


def test_an_unbounded_end_is_printed_open():
    # infinity is refused as a value (it is not finite), so the range must not say it is included
    half = limits.Range("ds", lo=0.0, lo_open=True)
    assert half.interval() == "(0, inf)"
    assert limits.Range("x", hi=1.0).interval() == "(-inf, 1]"
    with pytest.raises(ParameterError, match=r"^ds = 0 is outside the allowed range \(0, inf\)"):
        half.check(0.0)
    with pytest.raises(ParameterError, match=r"ds must be finite, got inf"):
        half.check(math.inf)


@pytest.mark.parametrize("value", [0.3, 1, np.float32(0.3), np.float64(0.3), np.int64(1), jnp.asarray(0.3),
                                   jnp.asarray(0.3, dtype=jnp.float32), np.asarray(0.3)])
def test_range_accepts_concrete_numbers(value):
    v = limits.SPEED.check(value)
    assert isinstance(v, float) and v == pytest.approx(float(value))


@pytest.mark.parametrize("value, match", [
    (float("nan"), "finite"), (float("inf"), "finite"), (True, "real number"), ("0.3", "real number"),
    (None, "real number"), (1 + 2j, "real number"), (np.array([0.1, 0.2]), "scalar"),
])
def test_range_refuses_non_numbers(value, match):
    with pytest.raises(ParameterError, match=match):
        limits.SPEED.check(value, "omega")


def test_integer_range():
    assert limits.NX.check(np.int64(16)) == 16 and type(limits.NX.check(np.int32(16))) is int
    assert limits.NX.check(jnp.asarray(16)) == 16
    for bad in (16.0, np.float64(16.0), True, "16"):
        with pytest.raises(ParameterError, match="Nx must be an integer"):
            limits.NX.check(bad)


def test_checks_are_skipped_for_tracers(small_params):
    @jax.jit
    def f(omega, p):
        limits.SPEED.check(omega)  # a tracer: not checked, no error at trace time
        return p.check().alpha_f * omega

    bad = eqx.tree_at(lambda q: q.alpha_f, jax.tree_util.tree_map(jnp.asarray, small_params), jnp.asarray(-0.1))
    assert float(f(jnp.asarray(60.0), bad)) == pytest.approx(-6.0)
    assert float(jax.grad(lambda a: limits.SPEED.check(a) * 2.0)(100.0)) == 2.0


def test_design_box_inside_the_physical_range():
    from gfbjax.design.evaluate import FOIL_BOUNDS

    for design, physical in ((limits.DESIGN_ALPHA_F, limits.ALPHA_F), (limits.DESIGN_ETA, limits.ETA)):
        assert physical.contains(design.lo) and physical.contains(design.hi)
        assert FOIL_BOUNDS[design.name] == (design.lo, design.hi)


# -- the Python API -----------------------------------------------------------------------------------------------


def test_system_spec_accepts_numpy_numbers():
    spec = gfbjax.SystemSpec(Nx=np.int64(16), Nz=np.int32(2), alpha_f=np.float32(0.5), R=jnp.asarray(0.02))
    assert type(spec.Nx) is int and type(spec.Nz) is int and type(spec.alpha_f) is float
    assert spec.Nx == 16 and spec.alpha_f == pytest.approx(0.5) and spec.R == pytest.approx(0.02)
    assert spec.nondim().Nx == 16
    with pytest.raises(ParameterError, match="Nx must be an integer"):
        gfbjax.SystemSpec(Nx=np.float64(16.0))


def test_grid_is_capped_by_the_dense_jacobians():
    t = time.perf_counter()
    with pytest.raises(ParameterError, match=r"Nx x Nz = 1024 x 256 has 262919 states.*\[1, 6144\]"):
        gfbjax.SystemSpec(Nx=1024, Nz=256)
    assert time.perf_counter() - t < 1.0
    # the corners of the per-axis ranges stay usable on their own
    assert gfbjax.SystemSpec(Nx=1024, Nz=2).Nx == 1024
    assert gfbjax.SystemSpec(Nx=16, Nz=256).Nz == 256
    n = limits.n_states(200, 20, 8)
    assert n == 4187 and limits.STATES.contains(n)  # the grid-convergence reference grid


@pytest.mark.parametrize("method", ["omega_bar", "rpm"])
@pytest.mark.parametrize("value", [float("nan"), float("inf"), "fast"])
def test_speed_conversions_refuse_non_finite(method, value):
    spec = gfbjax.reference_system()
    with pytest.raises(ParameterError, match="rpm|omega_bar"):
        getattr(spec, method)(value)
    assert spec.rpm(np.float32(0.3)) == pytest.approx(spec.rpm(0.3), rel=1e-6)
    np.testing.assert_allclose(spec.omega_bar(np.array([1000.0, 2000.0])), [spec.omega_bar(1000.0),
                                                                           spec.omega_bar(2000.0)])


@pytest.mark.parametrize("field, value", [
    ("alpha_f", -0.1), ("alpha_f", 0.0), ("eta", -0.05), ("eta", float("nan")), ("zeta", -1.0), ("kappa", 0.0),
    ("mass_ratio", -1.0), ("k_s", 0.0), ("sigma", -0.1), ("eps", -0.5),
])
def test_params_check_names_the_field(small_params, field, value):
    bad = eqx.tree_at(lambda q: getattr(q, field), small_params, jnp.asarray(value))
    with pytest.raises(ParameterError, match=rf"Params\.{field}"):
        bad.check()
    assert small_params.check() is small_params
    # a rigid rotor has no shaft or disc: k_s and mass_ratio are 0 and not checked
    gfbjax.SystemSpec(Nx=16, Nz=2, rotor="rigid").nondim().check()


def test_params_check_covers_replace_and_the_grid(small_params):
    with pytest.raises(ParameterError, match="alpha_f"):
        dataclasses.replace(small_params, alpha_f=-0.1).check()
    with pytest.raises(ParameterError, match="Nx"):
        dataclasses.replace(small_params, Nx=4).check()
    with pytest.raises(ParameterError, match="rotor"):
        dataclasses.replace(small_params, rotor="flexible").check()


def test_static_accepts_numpy_and_jax_speeds(small_params):
    from gfbjax.analyses.static import solve_equilibrium

    ref = solve_equilibrium(small_params, 0.3)
    assert ref.converged
    for omega in (jnp.asarray(0.3), np.float32(0.3), np.float64(0.3)):
        r = solve_equilibrium(small_params, omega, w=np.float64(0.0))
        assert r.converged and isinstance(r.omega, float)
        assert r.y_j == pytest.approx(ref.y_j, rel=1e-5)
    with pytest.raises(ParameterError, match=r"omega = 60 is outside the allowed range \(0, 50\]"):
        solve_equilibrium(small_params, jnp.asarray(60.0))
    with pytest.raises(ParameterError, match="guess_w"):
        solve_equilibrium(small_params, 0.3, 0.1, guess=ref.state, guess_w=-1.0)


def test_static_refuses_bad_params_before_solving(small_params, monkeypatch):
    import gfbjax.analyses.static as static

    monkeypatch.setattr(static, "newton_solve", lambda *a, **k: pytest.fail("solved with bad params"),
                        raising=False)
    bad = eqx.tree_at(lambda q: q.alpha_f, small_params, jnp.asarray(-0.1))
    with pytest.raises(ParameterError, match=r"Params\.alpha_f = -0\.1 is outside the allowed range \(0, 100\]"):
        static.solve_equilibrium(bad, 0.3)
    with pytest.raises(ParameterError, match="alpha_f"):
        static.load_displacement(bad, 0.3, [0.0, 0.1])


def test_toml_base_must_be_a_name(tmp_path, capsys, no_static_solve):
    cfg = tmp_path / "sys.toml"
    cfg.write_text('base = ["reference"]\nalpha_f = 0.2\n')
    with pytest.raises(ParameterError, match=r"base = \['reference'\].*must be the name"):
        gfbjax.load_config(cfg)
    code, _, err = _run(["static", "--system", str(cfg), *SMALL, "--out", str(tmp_path / "o")], capsys)
    assert code == 2 and "base" in _one_error_line(err)


# -- transient runs -------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("accel, match", [
    (1e-12, r"accel = 1e-12 per tau\^2 implies 7\.94e\+10 revolutions .* \(0, 1e\+06\]"),
    (0.0, r"\|accel\| = 0 per tau\^2 is outside the allowed range \(0, 100\]"),
    (-0.01, "wrong sign"),
    (float("nan"), "finite"),
    (1e3, r"\|accel\| = 1000"),
])
def test_run_up_acceleration_is_checked_first(small_params, monkeypatch, accel, match):
    import gfbjax.analyses.transient as tr

    monkeypatch.setattr(tr, "default_initial_state", lambda *a, **k: pytest.fail("computed before the checks"))
    with pytest.raises(ParameterError, match=match):
        tr.run_up(small_params, 0.05, 1.0, accel=accel)


def test_run_checks_accept_numpy_and_bound_the_history(small_params):
    from gfbjax.analyses.transient import TransientSettings, check_run_up, check_simulate

    plan = check_run_up(small_params, np.float32(0.05), jnp.asarray(1.0), accel=np.float64(0.01))
    assert plan.accel == 0.01 and plan.tau_end == pytest.approx((1.0 - 0.05) / 0.01, rel=1e-6)
    coast = check_run_up(small_params, 1.0, 0.5, revolutions=100)
    assert coast.accel < 0
    assert check_simulate(small_params, jnp.asarray(0.3), revolutions=np.int64(10)).omega0 == pytest.approx(0.3)
    with pytest.raises(ParameterError, match="saved samples"):
        check_simulate(small_params, 0.3, revolutions=1e6, settings=TransientSettings(samples_per_rev=4096))
    with pytest.raises(ParameterError, match="saved samples"):  # full states per sample: 56 x more memory
        check_simulate(small_params, 0.3, revolutions=1e6, settings=TransientSettings(save_states=True))
    with pytest.raises(ParameterError, match="revolutions"):
        check_simulate(small_params, 0.3, revolutions=0)
    with pytest.raises(ParameterError, match="tau_end"):
        check_simulate(small_params, 0.3, tau_end=-1.0)
    bad = eqx.tree_at(lambda q: q.eta, small_params, jnp.asarray(-1.0))
    with pytest.raises(ParameterError, match="eta"):
        check_run_up(bad, 0.05, 1.0)
    assert TransientSettings(samples_per_rev=np.int64(64), rtol=np.float32(1e-5)).samples_per_rev == 64


@pytest.mark.parametrize("argv, word", [
    (["--accel", "1e-12"], "--accel = 1e-12"),
    (["--accel", "0"], "|--accel| = 0"),
    (["--accel", "-0.01"], "--accel = -0.01 has the wrong sign"),
    (["--start", "1.0", "--end", "0.5", "--accel", "0.01"], "--accel = 0.01 has the wrong sign"),
    (["--revs", "1e6", "--samples-per-rev", "4096"], "saved samples"),
    (["--settle-revs", "-1"], "--settle-revs"),
    (["--start", "60"], "--start"),
    (["--start", "0.5", "--end", "0.5"], "--end"),
    (["--rtol", "0.5"], "--rtol = 0.5 is outside"),
    # the settings' own checks name the option, not the field (was "samples_per_rev = 1 ...")
    (["--samples-per-rev", "1"], "--samples-per-rev = 1 is outside"),
    (["--chunk-revs", "0"], "--chunk-revs = 0 is outside"),
    (["--h-rub", "-1"], "--h-rub = -1 is outside"),
])
def test_runup_cli_refuses_before_computing(argv, word, tmp_path, capsys, no_static_solve):
    t = time.perf_counter()
    code, _, err = _run(["runup", *SMALL, *argv, "--out", str(tmp_path / "o")], capsys)
    assert code == 2
    assert word in _one_error_line(err)
    assert not (tmp_path / "o").exists()
    assert time.perf_counter() - t < 30.0


# -- the command line ---------------------------------------------------------------------------------------------


def test_static_cli_grid_too_large(tmp_path, capsys, no_static_solve):
    code, _, err = _run(["static", "--nx", "1024", "--nz", "256", "--out", str(tmp_path / "o")], capsys)
    assert code == 2
    line = _one_error_line(err)
    assert "Nx x Nz = 1024 x 256" in line and "6144" in line


@pytest.mark.parametrize("argv, word", [
    (["static", *SMALL, "--curves", "--speeds", "0.2,0.2"], "values must be distinct, 0.2 repeated"),
    (["static", *SMALL, "--curves", "--alphas", "0.5,1,0.5"], "values must be distinct, 0.5 repeated"),
    (["static", *SMALL, "--curves", "--speeds", "0.2,,0.4"], "an empty item in '0.2,,0.4'"),
    (["static", *SMALL, "--out", ""], "--out: expected a folder, got an empty string"),
    (["coefficients", *SMALL, "--start", "0.3", "--end", "0.3", "--points", "3"],
     "--end must differ from --start = 0.3 for --points 3"),
])
def test_lists_and_folders_that_cannot_be_meant_are_refused(argv, word, tmp_path, capsys, no_static_solve,
                                                           monkeypatch):
    monkeypatch.chdir(tmp_path)  # an empty --out must not write into the current folder either
    if "--out" not in argv:
        argv = [*argv, "--out", str(tmp_path / "o")]
    code, _, err = _run(argv, capsys)
    assert code == 2
    assert word in _one_error_line(err)
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize("argv, word", [
    (["--nx", "16", "--set", "Nx=24"], "--nx 16 and --set Nx=24 disagree"),
    (["--nz", "2", "--set", "Nz=3"], "--nz 2 and --set Nz=3 disagree"),
])
def test_grid_given_twice_with_two_values_is_refused(argv, word, tmp_path, capsys, no_static_solve):
    code, _, err = _run(["static", *argv, "--out", str(tmp_path / "o")], capsys)
    assert code == 2
    assert word in _one_error_line(err)


def test_grid_given_twice_with_one_value_is_accepted():
    import argparse

    from gfbjax.cli.commands._common import spec_from_args

    args = argparse.Namespace(system="reference", overrides=["Nx=16"], nx=16, nz=None)
    assert spec_from_args(args).Nx == 16


def test_out_under_a_file_is_refused_before_computing(tmp_path, capsys, no_static_solve):
    blocker = tmp_path / "somefile"
    blocker.write_text("not a folder\n")
    code, _, err = _run(["static", *SMALL, "--out", str(blocker / "sub")], capsys)
    assert code == 2 and "--out" in _one_error_line(err)
    code, _, err = _run(["static", *SMALL, "--out", str(blocker)], capsys)
    assert code == 2 and "is not a folder" in _one_error_line(err)


def test_unwritable_out_is_refused_before_computing(tmp_path, capsys, monkeypatch, no_static_solve):
    # tests run as root, where chmod does not stop writes: make the probe file fail as on a read-only folder
    import tempfile

    def denied(*a, **k):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(tempfile, "TemporaryFile", denied)
    code, _, err = _run(["static", *SMALL, "--out", str(tmp_path / "ro")], capsys)
    assert code == 2
    assert "--out" in (line := _one_error_line(err)) and "not writable" in line and "Permission denied" in line


@pytest.mark.parametrize("argv, word", [
    (["--speed", "60"], "--speed = 60 is outside the allowed range (0, 50]"),
    (["--rpm", "nan"], "--rpm must be finite"),
    (["--rpm", "1e9"], "--rpm = 1e+09 rev/min is outside the allowed range"),
    (["--w", "25"], "--w = 25 is outside the allowed range [0, 20]"),
    (["--alphas", "0.1,-1"], "--alphas"),
    (["--set", "eta=0"], "eta = 0 is outside the allowed range (0, 100]"),
    (["--nx", "8"], "Nx = 8 is outside the allowed range [16, 1024]"),
])
def test_static_cli_messages_name_option_and_range(argv, word, tmp_path, capsys, no_static_solve):
    code, _, err = _run(["static", *SMALL, *argv, "--out", str(tmp_path / "o")], capsys)
    assert code == 2 and word in _one_error_line(err)


# -- the design code ----------------------------------------------------------------------------------------------


def test_design_checks(small_params):
    from gfbjax.design.evaluate import FoilDesign, check_foil
    from gfbjax.design.schedule import optimized_continuation

    assert check_foil(np.float32(0.5), jnp.asarray(0.05)) == (pytest.approx(0.5), pytest.approx(0.05))
    with pytest.raises(ParameterError, match=r"alpha_f = 3 is outside the allowed range \[0.005, 2\]"):
        check_foil(3.0, 0.05)
    bad = eqx.tree_at(lambda q: q.alpha_f, small_params, jnp.asarray(-0.1))
    with pytest.raises(ParameterError, match=r"Params\.alpha_f"):
        FoilDesign(bad, 0.3)
    with pytest.raises(ParameterError, match="omega"):
        FoilDesign(small_params, 60.0)
    with pytest.raises(ParameterError, match="omega_end"):
        optimized_continuation(small_params, 0.4, 0.3)
    with pytest.raises(ParameterError, match="omega_start"):
        optimized_continuation(small_params, math.nan, 0.3)


def test_a_system_spec_where_params_are_expected_is_a_clear_error():
    """Handing the SI SystemSpec to an analysis that takes the dimensionless Params gives a ParameterError that
    says to call nondim(), before any computation.  Before, an AttributeError ('SystemSpec' object has no attribute
    'check') came from inside (review: energy_map_stepped, FoilDesign)."""
    import gfbjax
    from gfbjax.design.evaluate import FoilDesign
    from gfbjax.design.maps import energy_map_stepped
    from gfbjax.params import ParameterError

    spec = gfbjax.reference_system(Nx=16, Nz=2)
    with pytest.raises(ParameterError, match="nondim"):
        energy_map_stepped(spec, 0.2, [0.1], [0.05])
    with pytest.raises(ParameterError, match="nondim"):
        FoilDesign(spec, 0.2)
    with pytest.raises(ParameterError, match="Params"):
        FoilDesign({"alpha_f": 0.1}, 0.2)


def test_equilibria_keep_the_settings_bounds_inside_the_range(small_params):
    """continue_gfb_equilibria replaced the settings' speed bounds by the range, so a lam_max of 0.3 with the
    range 0.2 -> 0.5 ran on to 0.5 (review list of issue 12); cycles already kept the narrower bound.  Now the
    branch ends on 0.3, and a start outside the settings' bounds is refused before any work."""
    from gfbjax import cont
    from gfbjax.analyses.cycles import continue_gfb_cycles, continue_gfb_equilibria, default_cycle_settings

    settings = cont.EquilibriumSettings(lam_max=0.3, max_points=40)
    br = continue_gfb_equilibria(small_params, 0.2, 0.5, settings)
    assert float(np.max(br.lam)) == pytest.approx(0.3, abs=1e-12)
    assert str(br.outcome) == str(cont.Outcome.REACHED_END)
    with pytest.raises(ParameterError, match="omega_start = 0.35 leaves no room"):
        continue_gfb_equilibria(small_params, 0.35, 0.5, settings)
    with pytest.raises(ParameterError, match="omega_start = 0.35 leaves no room"):
        continue_gfb_cycles(small_params, 0.35, 0.5, default_cycle_settings(lam_max=0.3))
    # review cases: a start on the bound it heads past, and settings of the wrong kind (AttributeError before)
    with pytest.raises(ParameterError, match="omega_start = 0.3 leaves no room towards omega_end = 0.5"):
        continue_gfb_cycles(small_params, 0.3, 0.5, default_cycle_settings(lam_max=0.3))
    with pytest.raises(ParameterError, match="settings must be CycleSettings or None, got EquilibriumSettings"):
        continue_gfb_cycles(small_params, 0.3, 0.5, cont.EquilibriumSettings())
    with pytest.raises(ParameterError, match="settings must be EquilibriumSettings or None, got dict"):
        continue_gfb_equilibria(small_params, 0.3, 0.5, {"lam_max": 0.4})


def test_hopf_cycles_refuse_params_of_another_system(small_params):
    """Review case: equilibria of one system and params of another (here the smoothed Gumbel condition) ended the
    Hopf cycles at once with 0 points and no reason; the branch records its params, so they are compared first
    (the unbalance eps aside: both problems are of the balanced system)."""
    from gfbjax import cont
    from gfbjax.analyses.cycles import continue_gfb_equilibria, continue_gfb_hopf_cycles

    eq = continue_gfb_equilibria(small_params, 0.3, 0.4, cont.EquilibriumSettings(max_points=2))
    other = gfbjax.SystemSpec(Nx=16, Nz=2, gumbel_width=1e-3).nondim()
    with pytest.raises(ParameterError, match=r"params are not the system the equilibria were computed for: "
                                             r"gumbel_width = 0\.001 \(the equilibria: 0\.0\)"):
        continue_gfb_hopf_cycles(other, eq, 0)
    with pytest.raises(ValueError, match="no HOPF"):  # the same system passes on to the Hopf point's own checks
        continue_gfb_hopf_cycles(dataclasses.replace(small_params, eps=0.0), eq, 0)
