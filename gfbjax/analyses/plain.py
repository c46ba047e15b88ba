"""Plain rigid 360-degree gas journal bearing: the validation model of docs/model.md.

Whirl integration uses an own L-stable SDIRK scheme rather than diffrax's Kvaerno5: with a dense Jacobian and
diffrax's VeryChord root finder Kvaerno5 rejected about half its steps and took 20-60 s per orbit on a 256-unknown
grid on the shared 2-core CPU (heavily loaded at the time), against a few seconds here (fixed steps, one LU per
step shared by the three stages).

A rigid, aligned journal in a plain cylindrical sleeve (no foil), isothermal compressible film, periodic in the
circumferential angle theta, ambient pressure at both bearing edges.  The film is discretised by the same
finite-difference Reynolds operator as the foil bearing (:func:`gfbjax.model.plain_bearing_rates`, second order)
on the half length (mid-plane symmetry), so this module validates the pressure equation of the GFB model.

Everything is dimensionless (docs/model.md):

* bearing number ``Lambda = 6 mu Omega R^2 / (p0 c^2)`` [-], identical to the speed ``Omega_bar = Omega t*``;
* journal position ``(x, y)`` over the radial clearance c [-]; eccentricity ratio ``eps = sqrt(x^2 + y^2)``;
* time ``tau = t / t*`` with ``t* = 6 mu R^2 / (p0 c^2)``; whirl frequency ``nu = omega_whirl t*`` [-];
* pressure ``p / p0`` [-]; ``kappa = R / L`` [-];
* force on the journal in units of ``p0 R L`` [-]; specific load ``W / (p0 L D) = |F| / 2`` [-] (``D = 2R``).

Public functions:

* :func:`plain_bearing_steady` — steady pressure by Newton's method (exact Jacobian by ``jax.jacfwd``), load and
  attitude angle;
* :func:`small_eccentricity_reference` — the independent closed form of docs/model.md (first order in eps);
* :func:`whirl_force` — time integration (L-stable SDIRK, exact Jacobian) with the journal on a prescribed
  circular orbit; the force in the rotating frame checks the time-dependent (squeeze) term of the Reynolds
  equation against the steady bearing at ``Lambda_eff = Lambda - 2 nu``.
"""

from __future__ import annotations

import math
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from .. import cont
from ..model import Grid, bearing_force, plain_bearing_rates
from .. import limits
from ..params import ParameterError

__all__ = [
    "PlainBearingResult",
    "WhirlResult",
    "plain_bearing_steady",
    "small_eccentricity_reference",
    "whirl_force",
]

# -- input checks (ranges of gfbjax.limits; skipped for tracers under jit/vmap) ---------------------------

def _is_concrete(v: Any) -> bool:
    """True for Python/NumPy scalars and concrete arrays (checks are skipped for tracers under jit/vmap)."""
    return not limits.is_traced(v)


def _check_real(name: str, value: Any, lo: float | None, hi: float | None, *, lo_open: bool = False,
                hi_open: bool = False, what: str = "") -> None:
    """A finite real scalar in the given range (an ad-hoc :class:`gfbjax.limits.Range`: these ranges belong to
    the plain-bearing functions alone)."""
    limits.Range(name, lo, hi, lo_open=lo_open, hi_open=hi_open, what=what).check(value)


def _check_grid(Nx: Any, Nz: Any) -> None:
    """The periodic grid: :data:`gfbjax.limits.PLAIN_NX`, :data:`~gfbjax.limits.NZ` and at most
    :data:`~gfbjax.limits.MAX_DENSE_UNKNOWNS` unknowns (dense Newton Jacobian)."""
    nx, nz = limits.PLAIN_NX.check(Nx), limits.NZ.check(Nz)
    limits.PLAIN_UNKNOWNS.check(nx * nz)


def _check_position(x: Any, y: Any) -> None:
    _check_real("x", x, -1.0, 1.0, lo_open=True, hi_open=True, what="journal position over clearance")
    _check_real("y", y, -1.0, 1.0, lo_open=True, hi_open=True, what="journal position over clearance")
    if _is_concrete(x) and _is_concrete(y):
        e = math.hypot(float(x), float(y))
        if e >= 0.95:
            raise ParameterError(f"eccentricity sqrt(x^2 + y^2) = {e:.6g} is outside the allowed range [0, 0.95) "
                                 "(the film must stay open)")


# -- steady bearing ---------------------------------------------------------------------------------------

class PlainBearingResult(eqx.Module):
    """Steady plain gas journal bearing (all dimensionless; a PyTree, so it can come out of jit/vmap).

    Attributes:
        theta: circumferential nodes [rad], shape (Nx,) (periodic: theta = 0 .. 2 pi - dtheta).
        z: axial nodes over L, edge 0 to mid-plane 1/2, shape (Nz + 1,).
        pressure: p/p0 on all nodes (edge included), shape (Nx, Nz + 1).
        force: gas force on the journal (F_x, F_y) over the whole length [p0 R L].
        force_rt: the same force along (radial, tangential) unit vectors of the journal displacement
            ``e_r = (x, y)/eps`` and ``e_t = (-y, x)/eps`` [p0 R L] (for a journal at (eps, 0): ``(F_x, F_y)``).
        load: specific load ``W/(p0 L D) = |F|/2`` [-].
        attitude_deg: attitude angle [deg], from the journal displacement to the direction opposite the force,
            counted in the direction of rotation: ``atan2(F_t, -F_r)`` (= ``atan2(F_y, -F_x)`` for a journal
            displaced along +x).
        converged: Newton converged (step below tolerance with a full step).
        residual: infinity norm of dp/dtau at the solution [-].
        iterations: Newton iterations.
    """

    theta: Array
    z: Array
    pressure: Array
    force: Array
    force_rt: Array
    load: Array
    attitude_deg: Array
    converged: Array
    residual: Array
    iterations: Array


def _force_rt(F: Array, x: Array, y: Array) -> Array:
    eps = jnp.hypot(x, y)
    safe = jnp.where(eps > 0.0, eps, 1.0)
    cr = jnp.where(eps > 0.0, x / safe, 1.0)
    sr = jnp.where(eps > 0.0, y / safe, 0.0)
    return jnp.stack([F[0] * cr + F[1] * sr, -F[0] * sr + F[1] * cr])


def _step_test(xtol: float, max_iter: int) -> cont.NewtonSettings:
    """Newton settings of the plain bearing's solves: converged on a full step below ``xtol`` (no residual check,
    no divergence test: the damping keeps the pressure positive and the iteration monotone)."""
    return cont.NewtonSettings(tol=0.0, atol_step=xtol, rtol_step=0.0, max_iter=max_iter, divergence=math.inf,
                               verify_residual=False)


@eqx.filter_jit
def _steady(Lambda: Array, x: Array, y: Array, kappa: Array, grid: Grid, gumbel: bool, xtol: float,
            max_iter: int) -> PlainBearingResult:
    shape = (grid.n_theta, grid.Nz)
    zero = jnp.zeros_like(x)

    def F(p: Array) -> Array:
        return plain_bearing_rates(p.reshape(shape), x, y, zero, zero, Lambda, kappa, grid).reshape(-1)

    def linearise(p):
        r = F(p)
        return jnp.max(jnp.abs(r)), jnp.linalg.solve(jax.jacfwd(F)(p), -r), None

    def damping(p, dp, _):  # keeps the pressure positive (a gas film cannot carry p <= 0)
        ratio = jnp.where(dp < 0.0, p / jnp.where(dp < 0.0, -dp, 1.0), jnp.inf)
        return jnp.minimum(1.0, 0.9 * jnp.min(ratio))

    p0 = jnp.ones(grid.n_pressure, dtype=jnp.result_type(Lambda, x, y, float))
    sol = cont.newton_solve(linearise, p0, _step_test(xtol, max_iter), damping=damping)
    p, k, done = sol.x, sol.iterations, sol.converged
    res = jnp.max(jnp.abs(F(p)))
    P = p.reshape(shape)
    theta = grid.theta(0.0)
    Fxy = bearing_force(P, theta, grid, 0.0, gumbel=gumbel)
    Frt = _force_rt(Fxy, x, y)
    converged = done & jnp.isfinite(res) & jnp.all(p > 0.0)
    return PlainBearingResult(
        theta=theta, z=jnp.concatenate([jnp.zeros(1), grid.z()]), pressure=grid.full_field(P), force=Fxy,
        force_rt=Frt, load=0.5 * jnp.hypot(Fxy[0], Fxy[1]),
        attitude_deg=jnp.degrees(jnp.arctan2(Frt[1], -Frt[0])), converged=converged, residual=res, iterations=k)


def plain_bearing_steady(Lambda: float | Array, x: float | Array, y: float | Array, kappa: float | Array,
                         Nx: int, Nz: int, *, gumbel: bool = False, xtol: float = 1e-12,
                         max_iter: int = 40) -> PlainBearingResult:
    """Steady pressure, force and attitude angle of the plain 360-degree gas journal bearing.

    Newton's method on ``dp/dtau = 0`` (finite-difference Reynolds equation, second order), exact Jacobian by
    ``jax.jacfwd``, damped so that the pressure stays positive, from ambient pressure.  ``Lambda``, ``x``, ``y``
    and ``kappa`` are traced: a loop over them does not recompile, and ``jax.vmap`` batches them (the grid and
    ``gumbel`` are static).

    Args:
        Lambda: bearing number ``6 mu Omega R^2 / (p0 c^2)`` (= Omega_bar) [-], in [-1000, 1000] (negative: the
            journal turns from y towards x; the mirror image of +|Lambda|).
        x, y: journal centre over the radial clearance [-]; eccentricity below 0.95.  The journal turns from x
            towards y.
        kappa: ``R / L`` [-], in (0, 100] (``L/D = 1 / (2 kappa)``).
        Nx: circumferential intervals over 2 pi, in [8, 1024].
        Nz: axial intervals over the half length, in [2, 256]; ``Nx * Nz <= 6144``.
        gumbel: integrate ``max(p - 1, 0)`` for the force (sub-ambient film carries no load) instead of ``p - 1``.
            A plain gas bearing runs full film: the default False is the model of docs/model.md.
        xtol: Newton step tolerance on p/p0 (infinity norm).
        max_iter: most Newton iterations.

    Returns:
        :class:`PlainBearingResult` (force in units of ``p0 R L``; load ``W/(p0 L D)``; attitude in degrees).
    """
    _check_real("Lambda", Lambda, -1000.0, 1000.0, what="bearing number")
    _check_position(x, y)
    _check_real("kappa", kappa, 0.0, 100.0, lo_open=True, what="R/L")
    _check_grid(Nx, Nz)
    _check_real("xtol", xtol, 0.0, 1e-3, lo_open=True)
    limits.Range("max_iter", 1, 1000, integer=True).check(max_iter)
    f = lambda v: jnp.asarray(v, dtype=float)  # noqa: E731
    return _steady(f(Lambda), f(x), f(y), f(kappa), Grid(int(Nx), int(Nz), periodic=True), bool(gumbel),
                   float(xtol), int(max_iter))


# -- closed form ------------------------------------------------------------------------------------------

def small_eccentricity_reference(Lambda: float | np.ndarray, L_over_D: float | np.ndarray
                                 ) -> tuple[np.ndarray | float, np.ndarray | float]:
    """First-order (small eccentricity) closed form of the plain gas journal bearing (docs/model.md; Al-Bender,
    Air Bearings, Sect. 9.3), independent of the finite-difference solver:

    ``G = (pi/2) [i Lambda / (1 + i Lambda)] [1 - tanh(s L/D) / (s L/D)]``, ``s = sqrt(1 + i Lambda)``.

    Args:
        Lambda: bearing number [-], > 0 (array or scalar).
        L_over_D: length over diameter [-], > 0.

    Returns:
        ``(W / (eps p0 L D), attitude angle [deg])`` with ``W/(eps p0 L D) = |G|`` and attitude
        ``atan2(Im G, Re G)`` (Re G along the line of centres, Im G normal to it, in the direction of rotation).
    """
    for name, v in (("Lambda", Lambda), ("L_over_D", L_over_D)):
        a = np.asarray(v, dtype=float)
        if not np.all(np.isfinite(a)) or np.any(a <= 0.0):
            raise ParameterError(f"{name} = {v!r} is outside the allowed range (0, inf)")
    lam = np.asarray(Lambda, dtype=float)
    ld = np.asarray(L_over_D, dtype=float)
    s = np.sqrt(1.0 + 1j * lam)
    a = s * ld
    G = 0.5 * np.pi * (1j * lam / (1.0 + 1j * lam)) * (1.0 - np.tanh(a) / a)
    W = np.abs(G)
    att = np.degrees(np.arctan2(G.imag, G.real))
    if W.ndim == 0:
        return float(W), float(att)
    return W, att


# -- whirl ------------------------------------------------------------------------------------------------

# Alexander's 3-stage SDIRK (SIAM J. Numer. Anal. 14, 1977): third order, L-stable, stiffly accurate.  L-stability
# damps the fast pressure modes of the start transient at any step; one LU of (I - dt gamma J) per step serves all
# three stages (simplified Newton).
_G = 0.43586652150845899942
_SDIRK_A = ((_G, 0.0, 0.0),
            ((1.0 - _G) / 2.0, _G, 0.0),
            (-1.5 * _G**2 + 4.0 * _G - 0.25, 1.5 * _G**2 - 5.0 * _G + 1.25, _G))
_SDIRK_C = (_G, (1.0 + _G) / 2.0, 1.0)


class WhirlResult(eqx.Module):
    """Force of the plain bearing on a prescribed circular whirl orbit, in the frame rotating with the journal
    (all dimensionless; forces in units of ``p0 R L``).

    Attributes:
        radial: mean over the last whirl period of ``F . e_r``, ``e_r = (cos nu tau, sin nu tau)`` [p0 R L].
        tangential: mean over the last period of ``F . e_t``, ``e_t = (-sin nu tau, cos nu tau)`` [p0 R L].
        samples: (radial, tangential) at the ``steps_per_period`` step ends of the last period, shape (n, 2).
        ripple: largest deviation of a sample from the mean over the last period [p0 R L]: residue of the start
            transient (the periodic grid model is rotation invariant, so the periodic state is constant in the
            rotating frame; measured ~1e-16).
        drift: change of the rotating-frame force over the last period (largest component of end minus start)
            [p0 R L]; small once the periodic state is reached.
        tau_end: end time [-].
        newton_iterations: largest number of simplified-Newton iterations of a stage.
        success: every stage's Newton iteration converged and the pressure stayed positive and finite.
    """

    radial: Array
    tangential: Array
    samples: Array
    ripple: Array
    drift: Array
    tau_end: Array
    newton_iterations: Array
    success: Array


@eqx.filter_jit
def _whirl(Lambda: Array, nu: Array, eps: Array, kappa: Array, grid: Grid, n_periods: int, steps_per_period: int,
           newton_tol: float, max_newton: int) -> WhirlResult:
    shape = (grid.n_theta, grid.Nz)
    theta = grid.theta(0.0)

    def rhs(tau, p):
        c, s = jnp.cos(nu * tau), jnp.sin(nu * tau)
        x, y = eps * c, eps * s
        vx, vy = -eps * nu * s, eps * nu * c
        return plain_bearing_rates(p.reshape(shape), x, y, vx, vy, Lambda, kappa, grid).reshape(-1)

    def rotating(tau, p):
        F = bearing_force(p.reshape(shape), theta, grid, 0.0, gumbel=False)
        c, s = jnp.cos(nu * tau), jnp.sin(nu * tau)
        return jnp.stack([F[0] * c + F[1] * s, -F[0] * s + F[1] * c])

    period = 2.0 * jnp.pi / jnp.abs(nu)
    dt = period / steps_per_period
    n = grid.n_pressure
    eye = jnp.eye(n)

    def step(carry, k):
        p, ok, itmax = carry
        t = k * dt
        J = jax.jacfwd(rhs, argnums=1)(t, p)
        lu = jax.scipy.linalg.lu_factor(eye - dt * _G * J)
        stage_newton = _step_test(newton_tol, max_newton)
        ks = []
        for i in range(3):
            ti = t + _SDIRK_C[i] * dt
            base = p + dt * sum((_SDIRK_A[i][j] * ks[j] for j in range(i)), jnp.zeros_like(p))

            def stage(Y, ti=ti, base=base):  # simplified Newton: the step's LU for every iteration
                G = Y - base - dt * _G * rhs(ti, Y)
                return jnp.max(jnp.abs(G)), jax.scipy.linalg.lu_solve(lu, -G), None

            sol = cont.newton_solve(stage, p, stage_newton)
            Y = sol.x
            ok = ok & sol.converged & jnp.all(Y > 0.0)
            itmax = jnp.maximum(itmax, sol.iterations)
            ks.append((Y - base) / (dt * _G))
        p_new = p + dt * sum((_SDIRK_A[2][j] * ks[j] for j in range(3)), jnp.zeros_like(p))
        return (p_new, ok, itmax), rotating(t + dt, p_new)

    p0 = jnp.ones(n, dtype=jnp.result_type(Lambda, nu, eps, float))
    n_steps = n_periods * steps_per_period
    (p_end, ok, itmax), history = jax.lax.scan(step, (p0, jnp.asarray(True), jnp.asarray(0)),
                                               jnp.arange(n_steps, dtype=p0.dtype))
    last = history[-steps_per_period:]  # step ends tau_end - period + dt .. tau_end: one period, uniformly
    mean = jnp.mean(last, axis=0)
    ripple = jnp.max(jnp.abs(last - mean))
    before = history[-steps_per_period - 1] if n_periods > 1 else rotating(0.0, p0)
    drift = jnp.max(jnp.abs(history[-1] - before))
    ok = ok & jnp.all(jnp.isfinite(history))
    return WhirlResult(radial=mean[0], tangential=mean[1], samples=last, ripple=ripple, drift=drift,
                       tau_end=n_steps * dt, newton_iterations=itmax, success=ok)


def whirl_force(Lambda: float | Array, nu: float | Array, eps: float | Array, kappa: float | Array, Nx: int,
                Nz: int, n_periods: int, *, steps_per_period: int = 96, newton_tol: float = 1e-12,
                max_newton: int = 10) -> WhirlResult:
    """Force of the plain gas bearing with the journal prescribed on a circular whirl orbit, in the rotating frame.

    The journal moves on ``x = eps cos(nu tau)``, ``y = eps sin(nu tau)`` (velocities ``-eps nu sin(nu tau)``,
    ``eps nu cos(nu tau)``; forward whirl for ``nu > 0``), starting from ambient pressure at ``tau = 0``.  The
    pressure ODE (finite-difference Reynolds equation with its squeeze term ``-p h'/h``) is integrated for
    ``n_periods`` whirl periods with an L-stable, third-order SDIRK scheme (Alexander 1977; the stiff diffusion
    modes of the grid are damped at any step) at ``steps_per_period`` fixed steps per period, each stage solved by
    simplified Newton with the exact Jacobian (``jax.jacfwd``).  The force is rotated into the frame of the
    journal and averaged over the last period.  Once the start transient has died out (the slowest pressure mode
    decays like ``exp(-kappa^2 pi^2 tau / 2)``, so integrate for ``tau >~ 20 / (kappa^2 pi^2)``) the force is
    constant in that frame and, by docs/model.md, equals the steady force (``force_rt`` of
    :func:`plain_bearing_steady`) at the effective bearing number ``Lambda - 2 nu``; zero at ``nu = Lambda/2``.
    On a grid of ``Nx`` intervals the relation holds with ``Lambda - 2 nu / s``, ``s = sin(dth)/dth``,
    ``dth = 2 pi / Nx`` (the squeeze term is exact in time, the Couette term a central difference), i.e. with
    ``Lambda - 2 nu`` up to a second-order grid error.
    ``ripple`` and ``drift`` measure how periodic the end state is.  The time-stepping error falls as
    ``steps_per_period^-3``: measured ~2e-4 of the force at 48 steps per period and ~2e-5 at the default 96
    (Lambda = 1, nu = 0.25, eps = 0.05).

    ``Lambda``, ``nu``, ``eps`` and ``kappa`` are traced (no recompilation in a loop over them); the grid,
    ``n_periods`` and ``steps_per_period`` are static.

    Args:
        Lambda: bearing number (= Omega_bar) [-], in [-1000, 1000] (negative: the journal turns from y to x).
        nu: whirl frequency ``omega_whirl t*`` [-], ``0 < |nu| <= 1000`` (negative: backward whirl).
        eps: orbit radius over the clearance [-], in (0, 0.9].
        kappa: ``R / L`` [-], in (0, 100].
        Nx, Nz: grid intervals (circumference over 2 pi; half length); see :func:`plain_bearing_steady`.
        n_periods: whirl periods to integrate, in [1, 1000].
        steps_per_period: fixed time steps per whirl period, in [8, 10000].
        newton_tol: stage Newton tolerance on p/p0 (infinity norm of the last update).
        max_newton: most Newton iterations per stage.

    Returns:
        :class:`WhirlResult` (forces in units of ``p0 R L``).
    """
    _check_real("Lambda", Lambda, -1000.0, 1000.0, what="bearing number")
    _check_real("nu", nu, -1000.0, 1000.0, what="whirl frequency")
    if _is_concrete(nu) and float(np.asarray(nu)) == 0.0:
        raise ParameterError("nu = 0.0 is outside the allowed range 0 < |nu| <= 1000 (a circular whirl needs a "
                             "non-zero frequency; use plain_bearing_steady for a fixed journal)")
    _check_real("eps", eps, 0.0, 0.9, lo_open=True, what="orbit radius over clearance")
    _check_real("kappa", kappa, 0.0, 100.0, lo_open=True, what="R/L")
    _check_grid(Nx, Nz)
    for name, v, lo, hi in (("n_periods", n_periods, 1, 1000), ("steps_per_period", steps_per_period, 8, 10000),
                            ("max_newton", max_newton, 1, 100)):
        limits.Range(name, lo, hi, integer=True).check(v)
    _check_real("newton_tol", newton_tol, 0.0, 1e-3, lo_open=True)
    f = lambda v: jnp.asarray(v, dtype=float)  # noqa: E731
    return _whirl(f(Lambda), f(nu), f(eps), f(kappa), Grid(int(Nx), int(Nz), periodic=True), int(n_periods),
                  int(steps_per_period), float(newton_tol), int(max_newton))
