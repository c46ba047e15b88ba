"""Plain rigid 360-degree gas journal bearing (gfbjax.analyses.plain) against docs/model.md.

References are independent of the finite-difference solver: the numbers printed in docs/model.md's table, the
closed form of Al-Bender (``small_eccentricity_reference``, itself checked against the printed table here), the
incompressible / short-bearing limits and the whirl relation ``Lambda_eff = Lambda - 2 nu``.

Measured errors of the solver (eps = 1e-3, L/D = 1, relative to the closed form; attitude in degrees):

    Lambda  grid      load error   attitude error
    0.5     (64,16)   -0.263 %     +0.004
    1       (64,16)   -0.259 %     +0.008
    5       (64,16)   -0.213 %     +0.001
    20      (64,16)   -0.226 %     -0.066
    1       (16,4) / (32,8) / (64,16):  -4.08 % / -1.03 % / -0.259 %  -> observed order 1.98, 2.00
    20      (16,4) / (32,8) / (64,16):  -3.68 % / -0.910 % / -0.226 % -> observed order 2.02, 2.01
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import gfbjax
from gfbjax import ParameterError
from gfbjax.analyses.plain import plain_bearing_steady, small_eccentricity_reference, whirl_force

jax.config.update("jax_enable_x64", True)

# docs/model.md, L/D = 1: Lambda -> (W / (eps p0 L D), attitude angle in degrees), as printed.
TABLE = {
    0.1: (0.0374, 88.38),
    0.5: (0.1853, 81.93),
    1.0: (0.3599, 74.19),
    2.0: (0.6493, 60.58),
    5.0: (1.0720, 36.08),
    10.0: (1.2471, 21.51),
    20.0: (1.3376, 13.24),
    50.0: (1.4204, 7.43),
    100.0: (1.4633, 4.90),
}
KAPPA_LD1 = 0.5  # R / L for L / D = 1
EPS = 1e-3  # small eccentricity: W / eps differs from the first-order value by O(eps^2) = 1e-6 (F is odd in eps)
GRID = (64, 16)  # second order; ~0.25 % load error (see module docstring), 0.1 s per solve


def _steady(Lambda, eps=EPS, kappa=KAPPA_LD1, grid=GRID, **kw):
    r = plain_bearing_steady(Lambda, eps, 0.0, kappa, *grid, **kw)
    assert bool(r.converged), (Lambda, eps, kappa, grid)
    return r


# -- (a) docs/model.md's table ---------------------------------------------------------------------------

@pytest.mark.parametrize("Lambda", list(TABLE))
def test_closed_form_reproduces_printed_table(Lambda):
    """The independent closed form reproduces every printed entry to its printed precision."""
    W, att = small_eccentricity_reference(Lambda, 1.0)
    W_tab, att_tab = TABLE[Lambda]
    assert abs(W - W_tab) <= 0.6e-4 + 1e-12
    assert abs(att - att_tab) <= 0.006


@pytest.mark.parametrize("Lambda", [0.5, 1.0, 5.0, 20.0])
def test_plain_bearing_matches_table(Lambda):
    r = _steady(Lambda)
    W = float(r.load) / EPS
    att = float(r.attitude_deg)
    W_tab, att_tab = TABLE[Lambda]
    assert abs(W / W_tab - 1.0) < 0.01
    assert abs(att / att_tab - 1.0) < 0.01
    W_cf, att_cf = small_eccentricity_reference(Lambda, 1.0)
    assert abs(W / W_cf - 1.0) < 0.005  # measured 0.21-0.26 %
    assert abs(att - att_cf) < 0.15  # measured <= 0.07 deg
    # load = |F| / 2 and attitude = atan2(F_y, -F_x) for a journal displaced along +x
    Fx, Fy = (float(v) for v in r.force)
    assert float(r.load) == pytest.approx(0.5 * math.hypot(Fx, Fy), rel=1e-12)
    assert att == pytest.approx(math.degrees(math.atan2(Fy, -Fx)), abs=1e-9)
    assert Fx < 0.0 and Fy > 0.0  # restoring, and ahead in the direction of rotation (+theta)


def test_pressure_field_and_force_quadrature():
    """Boundary values of the returned field, and the force recomputed here from it (trapezoid in z, periodic
    rectangle rule in theta)."""
    r = _steady(5.0, eps=0.3)
    P = np.asarray(r.pressure)
    theta, z = np.asarray(r.theta), np.asarray(r.z)
    assert P.shape == (GRID[0], GRID[1] + 1)
    np.testing.assert_allclose(P[:, 0], 1.0)  # bearing edge
    assert np.all(P > 0.0)
    col = 2.0 * np.trapezoid(P - 1.0, z, axis=1)
    dth = 2 * math.pi / GRID[0]
    F = -dth * np.array([np.sum(col * np.cos(theta)), np.sum(col * np.sin(theta))])
    np.testing.assert_allclose(np.asarray(r.force), F, rtol=1e-10, atol=1e-14)
    # the pressure peaks just before the minimum film (theta = 0) in the direction of rotation
    i_max = np.unravel_index(np.argmax(P), P.shape)[0]
    assert math.pi < theta[i_max] < 2 * math.pi


@pytest.mark.parametrize("Lambda", [1.0, 20.0])
def test_mesh_convergence_second_order(Lambda):
    W_cf, _ = small_eccentricity_reference(Lambda, 1.0)
    errors = []
    for grid in [(16, 4), (32, 8), (64, 16)]:
        errors.append(abs(float(_steady(Lambda, grid=grid).load) / EPS / W_cf - 1.0))
    orders = [math.log2(errors[0] / errors[1]), math.log2(errors[1] / errors[2])]
    assert all(1.8 <= p <= 2.2 for p in orders), (errors, orders)


def test_lambda_is_traced_no_recompile(monkeypatch):
    """A loop over Lambda (and x, y, kappa) reuses the compiled solver; jax.vmap batches it."""
    import gfbjax.analyses.plain as plain

    calls = []
    orig = plain.plain_bearing_rates

    def counting(*args, **kw):
        calls.append(1)
        return orig(*args, **kw)

    monkeypatch.setattr(plain, "plain_bearing_rates", counting)
    plain_bearing_steady(1.0, 0.01, 0.0, 0.5, 20, 5)  # a grid no other test uses: traced once here
    n_first = len(calls)
    assert n_first > 0
    for lam in (0.5, 2.0, 3.0):
        plain_bearing_steady(lam, 0.02, 0.01, 0.7, 20, 5)
    assert len(calls) == n_first
    loads = jax.vmap(lambda L: plain_bearing_steady(L, 0.01, 0.0, 0.5, 20, 5).load)(jnp.array([0.5, 3.0]))
    for lam, w in zip((0.5, 3.0), np.asarray(loads)):
        assert w == pytest.approx(float(plain_bearing_steady(lam, 0.01, 0.0, 0.5, 20, 5).load), rel=1e-10)


def test_rotation_invariance():
    """A journal displaced along any direction gives the same radial/tangential force and attitude."""
    r0 = _steady(2.0, eps=0.2, grid=(32, 8))
    phi = 1.1
    r1 = plain_bearing_steady(2.0, 0.2 * math.cos(phi), 0.2 * math.sin(phi), 0.5, 32, 8)
    np.testing.assert_allclose(np.asarray(r1.force_rt), np.asarray(r0.force_rt), rtol=1e-9)  # measured 1e-15
    assert float(r1.attitude_deg) == pytest.approx(float(r0.attitude_deg), abs=1e-6)


# -- (b) limits -----------------------------------------------------------------------------------------

def test_small_lambda_limit():
    """W/(p0 L D) -> 0.3745 Lambda eps and attitude -> 90 deg as Lambda -> 0 (L/D = 1)."""
    for lam, att_tol in ((0.01, 0.2), (0.001, 0.02)):
        r = _steady(lam)
        assert float(r.load) / (lam * EPS) == pytest.approx(0.3745, rel=0.01)
        # the attitude approaches 90 deg linearly in Lambda (closed form: 89.84 deg at 0.01, 89.984 at 0.001)
        assert abs(float(r.attitude_deg) - 90.0) < att_tol


def _short(lam, eps, ld):
    """docs/model.md's short-bearing, incompressible, full-film limit W/(p0 L D)."""
    return math.pi / 6.0 * lam * eps * ld**2 / (1.0 - eps**2) ** 1.5


def test_short_bearing_limit():
    """Short-bearing formula at small Lambda and L/D = 0.25 (kappa = 2).

    Where it applies: it is the limit Lambda -> 0 (incompressible; the gas film runs full, so the full-film
    version with (pi/6), twice Ocvirk's half-Sommerfeld value, is the right one) *and* L/D -> 0.  At finite L/D it
    overestimates the load: at small eps the closed form gives 1 - tanh(a)/a against a^2/3 (a = L/D), i.e. a factor
    0.9756 at L/D = 0.25 (-2.4 %), and the neglected circumferential flow matters more as the film narrows, so
    the shortfall grows with eps (measured -2.7 % at eps = 0.001, -3.8 % at 0.3, -5.4 % at 0.5 on (64,16), of
    which ~0.25 % is grid error).  Tolerance 6 % up to eps = 0.5; the shortfall must shrink roughly like (L/D)^2
    when L/D is halved, and the attitude is 90 deg (full film, incompressible: no radial force).
    """
    lam = 0.01
    ratios = {}
    for eps in (1e-3, 0.3, 0.5):
        r = _steady(lam, eps=eps, kappa=2.0)
        ratios[eps] = float(r.load) / _short(lam, eps, 0.25)
        assert abs(ratios[eps] - 1.0) < 0.06, ratios
        assert abs(float(r.attitude_deg) - 90.0) < 0.1
    assert ratios[1e-3] > ratios[0.3] > ratios[0.5]  # the short-bearing error grows with eccentricity
    # at small eps the finite-length correction is the closed form's one
    W_cf, _ = small_eccentricity_reference(lam, 0.25)
    assert ratios[1e-3] == pytest.approx(W_cf / (math.pi / 6.0 * lam * 0.25**2), rel=0.005)
    # halving L/D cuts the shortfall by ~4 (measured 3.3 with the grid error): the formula is the L/D -> 0 limit
    r8 = _steady(lam, eps=0.5, kappa=4.0)
    shortfall_8 = 1.0 - float(r8.load) / _short(lam, 0.5, 0.125)
    assert 0.0 < shortfall_8 < (1.0 - ratios[0.5]) / 2.5


# -- (c) whirl ------------------------------------------------------------------------------------------

WHIRL_LAMBDA, WHIRL_EPS = 1.0, 0.05
WHIRL_PERIODS, WHIRL_STEPS = 3, 48


@pytest.fixture(scope="module")
def whirl_runs():
    """Whirl forces and steady forces on two grids differing only in Nx (the whirl relation's discretisation
    error is circumferential).  3 periods: the start transient (decay ~exp(-1.23 tau)) is below 1e-13 at the end."""
    out = {}
    for Nx in (16, 32):
        for nu in (0.25, 0.75, 0.5):
            w = whirl_force(WHIRL_LAMBDA, nu, WHIRL_EPS, KAPPA_LD1, Nx, 4, WHIRL_PERIODS,
                            steps_per_period=WHIRL_STEPS)
            assert bool(w.success)
            out[Nx, nu] = np.array([float(w.radial), float(w.tangential)]), w
    return out


def _steady_rt(Lambda, Nx):
    return np.asarray(_steady(Lambda, eps=WHIRL_EPS, grid=(Nx, 4)).force_rt)


@pytest.mark.parametrize("nu", [0.25, 0.75])
def test_whirl_equals_steady_at_lambda_minus_2nu(whirl_runs, nu):
    """Forward whirl at nu: the rotating-frame force equals the steady force at Lambda - 2 nu.

    Tolerance from the grid error: the squeeze term of the grid model is exact in time (p' and h' analytic) while
    the Couette term is a central difference, which sees the first harmonic e^{i theta} scaled by
    s = sin(dth)/dth.  On a grid the relation therefore holds with Lambda* = Lambda - 2 nu / s exactly (linear
    regime; O(eps^2) harmonics aside), and with Lambda - 2 nu up to O(dth^2) -> 0.  Both are asserted: the first
    to the time-stepping error (measured 1.6e-4 of the force at 48 steps per period, 3rd order), the second at
    Nx = 32 within 2.5 % (measured 0.60 % and 1.85 %) with an observed ratio of ~4 from Nx = 16 to 32.
    """
    scale = np.linalg.norm(_steady_rt(WHIRL_LAMBDA, 32))
    disc = {}
    for Nx in (16, 32):
        F_w, w = whirl_runs[Nx, nu]
        assert float(w.drift) < 1e-8 * scale  # periodic steady state reached
        s = math.sin(2 * math.pi / Nx) / (2 * math.pi / Nx)
        F_discrete = _steady_rt(WHIRL_LAMBDA - 2 * nu / s, Nx)
        assert np.linalg.norm(F_w - F_discrete) < 1e-3 * np.linalg.norm(F_discrete)
        F_eff = _steady_rt(WHIRL_LAMBDA - 2 * nu, Nx)
        disc[Nx] = np.linalg.norm(F_w - F_eff) / np.linalg.norm(F_eff)
    assert disc[32] < 0.025
    assert 3.3 < disc[16] / disc[32] < 4.7, disc
    # the tangential force changes sign with Lambda - 2 nu (whirl faster than half speed drives the orbit)
    assert np.sign(whirl_runs[32, nu][0][1]) == np.sign(WHIRL_LAMBDA - 2 * nu)


def test_half_frequency_whirl_carries_no_load(whirl_runs):
    load_static = np.linalg.norm(_steady_rt(WHIRL_LAMBDA, 32))
    F_half = {Nx: whirl_runs[Nx, 0.5][0] for Nx in (16, 32)}
    assert np.linalg.norm(F_half[32]) < 0.01 * load_static  # measured 0.66 %: grid error only
    assert 3.3 < np.linalg.norm(F_half[16]) / np.linalg.norm(F_half[32]) < 4.7  # -> 0 at second order
    # and it is exactly the grid's residual bearing number Lambda (1 - 1/s)
    s = math.sin(2 * math.pi / 32) / (2 * math.pi / 32)
    F_pred = _steady_rt(WHIRL_LAMBDA * (1 - 1 / s), 32)
    assert np.linalg.norm(F_half[32] - F_pred) < 0.02 * np.linalg.norm(F_pred)


# -- input checks ---------------------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, field", [
    (dict(Lambda=float("nan")), "Lambda"),
    (dict(Lambda=2000.0), "Lambda"),
    (dict(x=1.2), "x"),
    (dict(x=0.7, y=0.7), "eccentricity"),
    (dict(kappa=0.0), "kappa"),
    (dict(Nx=4), "Nx"),
    (dict(Nz=8.0), "Nz"),
    (dict(Nx=512, Nz=64), "Nx * Nz"),
])
def test_steady_input_checks(kwargs, field):
    args = dict(Lambda=1.0, x=0.1, y=0.0, kappa=0.5, Nx=16, Nz=4)
    args.update(kwargs)
    with pytest.raises(ParameterError, match=field.replace("*", r"\*")):
        plain_bearing_steady(args.pop("Lambda"), args.pop("x"), args.pop("y"), args.pop("kappa"), **args)


@pytest.mark.parametrize("kwargs, field", [
    (dict(nu=0.0), "nu"),
    (dict(eps=0.0), "eps"),
    (dict(eps=0.95), "eps"),
    (dict(n_periods=0), "n_periods"),
    (dict(steps_per_period=2), "steps_per_period"),
])
def test_whirl_input_checks(kwargs, field):
    args = dict(Lambda=1.0, nu=0.3, eps=0.1, kappa=0.5, Nx=16, Nz=4, n_periods=1)
    args.update(kwargs)
    with pytest.raises(ParameterError, match=field):
        whirl_force(**args)


def test_reference_input_checks():
    with pytest.raises(ParameterError, match="L_over_D"):
        small_eccentricity_reference(1.0, 0.0)
    with pytest.raises(ParameterError, match="Lambda"):
        small_eccentricity_reference(-1.0, 1.0)
    W, att = small_eccentricity_reference(np.array([1.0, 5.0]), 1.0)
    np.testing.assert_allclose(W, [TABLE[1.0][0], TABLE[5.0][0]], atol=1e-4)
    assert isinstance(gfbjax.ParameterError("x"), ValueError)
