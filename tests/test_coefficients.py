"""Linearised bearing coefficients (gfbjax.analyses.coefficients) and their export to ROSS.

References do not come from the code under test:

(a) the plain rigid 360-degree bearing against the closed-form small-eccentricity solution of the linearised
    compressible Reynolds equation (derived in the module doc; the closed form is checked here against the
    independent static closed form of Al-Bender in gfbjax.analyses.plain and against the incompressible limit
    computed from its elementary formula ``C_xx = 2 pi g0``, ``K_xy = pi g0 Lambda``, ``g0 = 1 - tanh(L/D)/(L/D)``).
    Measured on the (32, 8) grid, L/D = 1: largest entry error 0.74 / 1.19 / 1.42 % of the largest entry at
    (Lambda, nu) = (0.5, 1.5) / (1, 0.5) / (5, 2); second order (error ratio (16,4)/(32,8) 3.95 - 3.97).
(b) the Jeffcott rotor assembled from the frequency-dependent coefficients against the Hopf point that
    continue_gfb_equilibria locates on the full Jacobian (24 x 3 grid): measured agreement 2e-9 in speed and
    3e-10 in whirl frequency; the test allows 1e-6 (the condensation is exact on the imaginary axis).
(c) ROSS (finite-element rotor, its own eigen-solver and log decrement) on two exported bearings against the same
    Hopf point: measured +0.062 % in speed and +0.003 % in whirl frequency (9 tabulated speeds, cubic spline;
    -0.019 % and -0.002 % with 17); the test allows 0.5 %.
"""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

import gfbjax
from gfbjax import ParameterError
from gfbjax.analyses.coefficients import (bearing_coefficients, coefficient_hopf, coefficients_at,
                                          gfb_linearisation, impedance, plain_bearing_coefficients,
                                          small_eccentricity_coefficients)
from gfbjax.analyses.plain import small_eccentricity_reference
from gfbjax.model.bump import bump_parameter_for_compliance
from gfbjax.params import bump_foil_compliance

KAPPA = 0.5  # R/L for L/D = 1


def _g0(ld):
    return 1.0 - math.tanh(ld) / ld


# -- (a) the closed form and the plain bearing ---------------------------------------------------------------------

@pytest.mark.parametrize("Lambda", [0.5, 2.0, 10.0])
def test_closed_form_static_limit_is_al_bender(Lambda):
    """nu -> 0: the stiffness is that of the static closed form, F_x = -2 X Re G, F_y = 2 X Im G."""
    K, C = small_eccentricity_coefficients(Lambda, 1e-7, 1.0)
    W, att = small_eccentricity_reference(Lambda, 1.0)
    G = W * np.exp(1j * math.radians(att))
    assert K[0, 0] == pytest.approx(2 * G.real, rel=1e-6)
    assert K[1, 0] == pytest.approx(-2 * G.imag, rel=1e-6)
    assert K[1, 1] == pytest.approx(K[0, 0], rel=1e-12) and K[0, 1] == pytest.approx(-K[1, 0], rel=1e-12)


@pytest.mark.parametrize("L_over_D", [0.5, 1.0, 3.0])
def test_closed_form_incompressible_limit(L_over_D):
    """Small Lambda and nu: K_xx -> 0, K_xy = pi g0 Lambda, C_xx = 2 pi g0 (12 pi g0 mu R^3 L / c^3 in SI)."""
    lam = nu = 1e-4
    K, C = small_eccentricity_coefficients(lam, nu, L_over_D)
    g0 = _g0(L_over_D)
    assert C[0, 0] == pytest.approx(2 * math.pi * g0, rel=1e-4)
    assert K[0, 1] == pytest.approx(math.pi * g0 * lam, rel=1e-4)
    assert abs(K[0, 0]) < 1e-6 * C[0, 0]


@pytest.mark.parametrize("Lambda", [0.2, 2.0, 20.0])
def test_closed_form_half_frequency_whirl_carries_no_force(Lambda):
    """A forward circular whirl at nu = Lambda/2 feels no effective stiffness and no effective damping."""
    nu = Lambda / 2
    K, C = small_eccentricity_coefficients(Lambda, nu, 1.0)
    scale = abs(K).max() + nu * abs(C).max()
    assert abs(K[0, 0] + nu * C[0, 1]) < 1e-12 * scale
    assert abs(K[0, 1] - nu * C[0, 0]) < 1e-12 * scale
    K2, C2 = small_eccentricity_coefficients(Lambda, 0.8 * nu, 1.0)  # but off it the film does push
    assert abs(K2[0, 1] - 0.8 * nu * C2[0, 0]) > 1e-3 * scale


@pytest.mark.parametrize("Lambda,nu", [(1.0, 0.5), (5.0, 2.0), (0.5, 1.5)])
def test_plain_bearing_matches_closed_form_second_order(Lambda, nu):
    Ka, Ca = small_eccentricity_coefficients(Lambda, nu, 1.0)
    ref = np.concatenate([Ka.ravel(), nu * Ca.ravel()])
    errs = []
    for grid in ((16, 4), (32, 8)):
        K, C = plain_bearing_coefficients(Lambda, nu, KAPPA, *grid)
        errs.append(np.max(np.abs(np.concatenate([K.ravel(), nu * C.ravel()]) - ref)) / np.max(np.abs(ref)))
    assert errs[1] < 0.02
    assert errs[0] / errs[1] > 3.0  # second-order scheme


def test_plain_bearing_is_isotropic_when_centred():
    K, C = plain_bearing_coefficients(2.0, 0.7, KAPPA, 16, 4)
    for M in (K, C):
        assert M[1, 1] == pytest.approx(M[0, 0], rel=1e-9)
        assert M[0, 1] == pytest.approx(-M[1, 0], rel=1e-9)


def test_plain_bearing_half_frequency_on_the_grid():
    """On a grid the squeeze term is exact and the Couette term a central difference: half-frequency whirl sits at
    nu = s Lambda / 2, s = sin(dth)/dth (gfbjax.analyses.plain.whirl_force)."""
    Nx, Lam = 32, 2.0
    dth = 2 * math.pi / Nx
    nu = math.sin(dth) / dth * Lam / 2
    K, C = plain_bearing_coefficients(Lam, nu, KAPPA, Nx, 8)
    scale = abs(K).max()
    assert abs(K[0, 0] + nu * C[0, 1]) < 1e-9 * scale
    assert abs(K[0, 1] - nu * C[0, 0]) < 1e-9 * scale


# -- the gas foil bearing ---------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def g0_24x3():
    spec = gfbjax.variation("G0", Nx=24, Nz=3)
    return spec, spec.nondim()


def test_quasi_static_stiffness_is_the_load_deflection_slope(g0_24x3):
    """nu -> 0 stiffness against two static Newton solves under a small extra load (a different code path):
    dx_j = -K0^{-1} (0, dW) with dW = 2 dw in p0 R L."""
    from gfbjax.analyses.static import solve_equilibrium

    spec, p = g0_24x3
    om, dw = 0.3, 1e-5
    K0, _, eq0 = coefficients_at(p, om, 1e-7)
    eq1 = solve_equilibrium(p.traced(), om, dw, guess=eq0.state)
    eqm = solve_equilibrium(p.traced(), om, 0.0, guess=eq0.state, guess_w=0.0)
    d_fd = (np.array([eq1.x_j, eq1.y_j]) - np.array([eqm.x_j, eqm.y_j]))
    d_lin = -np.linalg.solve(K0, np.array([0.0, 2 * dw]))
    assert np.allclose(d_fd, d_lin, rtol=2e-3, atol=1e-3 * np.abs(d_lin).max())


def test_si_conversion_and_shapes(g0_24x3):
    spec, p = g0_24x3
    co = bearing_coefficients(p, [0.2, 0.3], whirl_ratio=0.5)
    assert co.K.shape == (2, 2, 2) and co.C.shape == (2, 2, 2)
    assert np.allclose(co.nu, [0.1, 0.15])
    si = co.si(spec)
    assert np.allclose(si["K_N_per_m"], co.K * spec.p0 * spec.R * spec.L / spec.c)
    assert np.allclose(si["C_Ns_per_m"], co.C * spec.p0 * spec.R * spec.L * spec.t_star / spec.c)
    assert np.allclose(si["speed_rpm"], np.array([0.2, 0.3]) / spec.t_star * 60 / (2 * math.pi))
    d = co.to_dict(spec)
    assert d["SI"]["kxy"][1] == pytest.approx(si["K_N_per_m"][1, 0, 1])
    K1, C1, _ = coefficients_at(p, 0.3, 0.15, equilibrium=co.equilibria[1])
    assert np.allclose(K1, co.K[1]) and np.allclose(C1, co.C[1])


@pytest.mark.parametrize("call", [
    lambda p: bearing_coefficients(p, [0.3], whirl_ratio=0.0),
    lambda p: bearing_coefficients(p, [60.0]),
    lambda p: coefficients_at(p, 0.3, -1.0),
    lambda p: coefficient_hopf(p, 0.5, 0.3),
])
def test_bad_input_raises_before_work(g0_24x3, call):
    with pytest.raises(ParameterError):
        call(g0_24x3[1])


@pytest.fixture(scope="module")
def hopf_24x3(g0_24x3):
    from gfbjax.analyses.cycles import continue_gfb_equilibria

    spec, p = g0_24x3
    br = continue_gfb_equilibria(p.traced(), 0.3, 0.5, spec=spec)
    h = br.special_of("HOPF")
    assert h and h[0].located
    return float(h[0].lam), float(h[0].omega), br


def test_coefficient_rotor_predicts_the_hopf_point(g0_24x3, hopf_24x3):
    """(b) the rotor built from K(nu), C(nu) loses stability where the full model does, at the same frequency."""
    spec, p = g0_24x3
    lam_h, nu_h, _ = hopf_24x3
    ch = coefficient_hopf(p, 0.3, 0.5)
    assert ch.omega == pytest.approx(lam_h, rel=1e-6)
    assert ch.nu == pytest.approx(nu_h, rel=1e-6)
    # and the coefficient rotor's eigenvalue there is i nu: the frequency-dependent impedance at that nu
    eq = coefficients_at(p, ch.omega, ch.nu)[2]
    K, C = impedance(gfb_linearisation(p, ch.omega, eq.state), ch.nu)
    assert np.allclose(K, ch.K) and np.allclose(C, ch.C)


# -- (c) ROSS ---------------------------------------------------------------------------------------------------

def _ross_or_skip():
    from gfbjax.analyses.coefficients import _ross

    try:
        _ross()
    except Exception as exc:  # noqa: BLE001 - any import failure of the optional extra
        pytest.skip(f"ross-rotordynamics not importable ({type(exc).__name__}: {exc}); "
                    "pip install 'gfbjax[ross]'")


def test_ross_bearing_element_carries_the_si_coefficients(g0_24x3):
    _ross_or_skip()
    from gfbjax.analyses.coefficients import ross_bearing

    spec, p = g0_24x3
    co = bearing_coefficients(p, np.linspace(0.2, 0.5, 5))
    b = ross_bearing(co, spec, n=0)
    si = co.si(spec)
    w = si["speed_rad_s"][2]
    assert np.allclose(b.K(w)[:2, :2], si["K_N_per_m"][2], rtol=1e-12)
    assert np.allclose(b.C(w)[:2, :2], si["C_Ns_per_m"][2], rtol=1e-12)
    with pytest.raises(ParameterError):
        ross_bearing(bearing_coefficients(p, [0.3]), spec, n=0)


def test_ross_round_trip_finds_the_hopf_point(g0_24x3, hopf_24x3):
    """(c) ROSS's log decrement of the whirl mode crosses zero at gfbjax's Hopf speed and frequency."""
    _ross_or_skip()
    from gfbjax.analyses.coefficients import ross_instability_onset

    spec, _ = g0_24x3
    lam_h, nu_h, _ = hopf_24x3
    onset = ross_instability_onset(spec, 0.3, 0.5, n_speeds=9)
    assert onset.omega_bar(spec) == pytest.approx(lam_h, rel=5e-3)
    assert onset.whirl_rad_s * spec.t_star == pytest.approx(nu_h, rel=5e-3)
    assert onset.rpm() == pytest.approx(spec.rpm(lam_h), rel=5e-3)


# -- bump foil both ways --------------------------------------------------------------------------------------------

GEOM = dict(l0=1.5e-3, t_b=1e-4, s0=4.5e-3, E=214e9)
MATERIAL = dict(nu=0.29, p0=1e5, c=38.1e-6)


@pytest.mark.parametrize("name", ["t_b", "l0", "s0", "E"])
def test_bump_round_trip(name):
    alpha = bump_foil_compliance(GEOM["l0"], GEOM["t_b"], GEOM["s0"], GEOM["E"], **MATERIAL)
    known = {k: v for k, v in GEOM.items() if k != name}
    assert bump_parameter_for_compliance(alpha, name, **known, **MATERIAL) == pytest.approx(GEOM[name], rel=1e-12)
    # and a compliance 8 times larger means a foil half as thick
    if name == "t_b":
        assert bump_parameter_for_compliance(8 * alpha, name, **known, **MATERIAL) == pytest.approx(
            GEOM["t_b"] / 2, rel=1e-12)


@pytest.mark.parametrize("alpha,name,word", [(1e-5, "t_b", "t_b = "), (50.0, "l0", "l0 = "), (0.01, "s0", "s0 = "),
                                             (0.0, "t_b", "alpha_f"), (0.3, "x", "solve_for")])
def test_bump_impossible_inputs_name_the_parameter(alpha, name, word):
    known = {k: v for k, v in GEOM.items() if k != name}
    with pytest.raises(ParameterError, match=word):
        bump_parameter_for_compliance(alpha, name, **known, **MATERIAL)


# -- command line -------------------------------------------------------------------------------------------------

def _cli(*argv, tmp_path):
    return subprocess.run([sys.executable, "-m", "gfbjax", *argv, "--out", str(tmp_path)], capture_output=True,
                          text=True, timeout=600)


def test_cli_speed_in_omega_bar_that_looks_like_rpm_gets_a_hint(tmp_path):
    r = _cli("cycles", "--start", "10000", tmp_path=tmp_path)
    assert r.returncode == 2
    assert "did you mean --start-rpm 10000 (= Omega_bar 0.2827)?" in r.stderr
    r = _cli("equilibria", "--start-rpm", "1e8", tmp_path=tmp_path)
    assert r.returncode == 2 and "--start-rpm = 1e+08 rev/min is outside" in r.stderr


def test_cli_rpm_options_convert_with_t_star(tmp_path):
    import argparse

    from gfbjax.cli.commands import _common, runup

    spec = gfbjax.reference_system()
    parser = argparse.ArgumentParser()
    runup.register(parser.add_subparsers())
    args = parser.parse_args(["runup", "--start-rpm", "5000", "--end", "0.6"])
    _common.resolve_speeds(args, spec, "--start", "--end")
    assert args.start == pytest.approx(spec.omega_bar(5000.0), rel=1e-12)
    assert args.end == 0.6


def test_cli_bump_both_ways(tmp_path):
    r = _cli("bump", "--l0", "1.5e-3", "--t-b", "1e-4", "--s0", "4.5e-3", tmp_path=tmp_path)
    assert r.returncode == 0, r.stderr
    alpha = json.loads((tmp_path / "bump.json").read_text())["alpha_f"]
    assert alpha == pytest.approx(bump_foil_compliance(1.5e-3, 1e-4, 4.5e-3, 214e9, 0.29, 1e5, 38.1e-6), rel=1e-12)
    r = _cli("bump", "--alpha-f", str(alpha), "--solve-for", "s0", "--l0", "1.5e-3", "--t-b", "1e-4",
             tmp_path=tmp_path)
    assert r.returncode == 0, r.stderr
    assert json.loads((tmp_path / "bump.json").read_text())["geometry"]["s0_m"] == pytest.approx(4.5e-3, rel=1e-9)
    r = _cli("bump", "--alpha-f", "1e-5", "--l0", "1.5e-3", "--s0", "4.5e-3", tmp_path=tmp_path)
    assert r.returncode == 2 and "t_b = " in r.stderr and "allowed range" in r.stderr


def test_cli_coefficients_writes_si_table(tmp_path):
    r = _cli("coefficients", "--nx", "16", "--nz", "2", "--start-rpm", "8000", "--end-rpm", "12000", "--points",
             "2", "--no-figures", tmp_path=tmp_path)
    assert r.returncode == 0, r.stderr
    d = json.loads((tmp_path / "coefficients.json").read_text())
    spec = gfbjax.reference_system(Nx=16, Nz=2)
    si = d["coefficients"]["SI"]
    assert si["speed_rpm"] == pytest.approx([8000.0, 12000.0], rel=1e-9)
    assert si["kxx"][0] == pytest.approx(d["coefficients"]["kxx"][0] * spec.force_scale / spec.c, rel=1e-12)
    rows = (tmp_path / "coefficients.csv").read_text().splitlines()
    assert len(rows) == 3 and rows[0].startswith("Omega_bar,rpm")


# -- figures: secondary rpm axis -------------------------------------------------------------------------------------

def test_speed_plots_get_an_rpm_axis(g0_24x3, hopf_24x3):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from gfbjax.plot.coefficients import plot_coefficients

    spec, p = g0_24x3
    co = bearing_coefficients(p, [0.2, 0.3])
    fig = plot_coefficients(co, spec=spec)
    sec = fig.axes[0].child_axes
    assert len(sec) == 1 and sec[0].get_xlabel() == "speed [rpm]"
    # the secondary axis maps Omega_bar to rpm with the system's t*
    assert sec[0]._functions[0](np.array([0.3]))[0] == pytest.approx(spec.rpm(0.3), rel=1e-12)
    plt.close(fig)
    fig = plot_coefficients(co)  # without the conversion: no rpm axis
    assert not fig.axes[0].child_axes
    plt.close(fig)
    from gfbjax.plot.branch import plot_equilibria

    fig = plot_equilibria(hopf_24x3[2])  # the branch knows its system (computed with spec=): rpm axis on top
    sec = fig.axes[0].child_axes
    assert len(sec) == 1 and sec[0]._functions[0](np.array([0.4]))[0] == pytest.approx(spec.rpm(0.4), rel=1e-12)
    plt.close(fig)
