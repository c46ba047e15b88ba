"""Static equilibria of the balanced GFB-rotor system (paper Sect. 3.1, Figs. 4-5).

An equilibrium solves ``f(s, Omega_bar) = 0`` for the balanced vector field (no unbalance), all states at once
(pressures, foil strips, rotor positions and zero velocities), by Newton's method with the exact Jacobian from
``jax.jacfwd`` and a backtracking line search that keeps the film open (h > 0).  From an ambient, centred start
the gravity and the extra load are switched on gradually (a homotopy in the load), which makes the solve robust
down to the speeds and up to the loads where the film nearly closes.  The Jacobian's eigenvalues at the solution
give the linear stability of the equilibrium.

Loads: ``w`` is the extra vertical *specific* load per bearing over ambient pressure, ``W / (p0 L D)`` [-], added
to gravity (paper Fig. 4).  In the equations of motion it enters as ``w_ext = W / (p0 R L) = 2 w``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from .. import cont
from ..cont import Outcome
from ..model import balanced_vector_field, film, layout
from .. import limits
from ..params import Params, SystemSpec, check_params

__all__ = ["StaticResult", "newton_solve", "solve_equilibrium", "load_displacement",
           "with_load"]

# Backtracking fractions of the Newton step, tried together (one vmapped evaluation).
_STEP_FRACTIONS = jnp.array([1.0, 0.5, 0.25, 0.125, 1 / 16, 1 / 64])


def with_load(params: Params, w: float | Array, scale: float | Array = 1.0) -> Params:
    """Params with the extra specific load ``w = W/(p0 L D)`` and gravity both multiplied by ``scale``."""
    return eqx.tree_at(lambda p: (p.w_ext, p.sigma), params,
                       (2.0 * jnp.asarray(w, jnp.float64) * scale, jnp.asarray(params.sigma * scale, jnp.float64)))


_jacobian = eqx.filter_jit(jax.jacfwd(balanced_vector_field))


def _h_min(s: Array, params: Params) -> Array:
    return jnp.min(film(s, params))


# Converged when a full step is below xtol (tol=inf: the last evaluation only reports the residual at the returned
# state); no divergence test (the damping keeps the iteration monotone).
def _newton_settings(xtol: float, max_iter: int) -> cont.NewtonSettings:
    return cont.NewtonSettings(tol=math.inf, atol_step=xtol, rtol_step=0.0, max_iter=max_iter,
                               divergence=math.inf)


@eqx.filter_jit
def newton_solve(s0: Array, omega: Array, params: Params, *, xtol: float = 1e-10, max_iter: int = 25
                 ) -> cont.NewtonSolution:
    """Damped Newton on the balanced vector field ``f(s, omega) = 0`` from ``s0``: the one corrector of
    :mod:`gfbjax.cont` with this damping.

    Each iteration solves ``J ds = -f`` with ``J = jax.jacfwd(f)`` and takes the largest step fraction t in
    ``{1, 1/2, ..., 1/64}`` that keeps the film open and passes Deuflhard's affine-invariant monotonicity test
    ``|J^-1 f(s + t ds)| <= (1 - t/4) |ds|`` (the simplified Newton correction shrinks; one LU serves all trial
    steps).  The test is blind to the very different scales of pressure, foil and rotor residuals, where a plain
    ``|f|`` line search crawls.  Converged when a full step has ``|ds|_inf <= xtol``; ``NONFINITE`` when no trial
    step keeps the film open and finite.  Pure and jit-compiled: ``jax.vmap`` batches it over guesses, speeds or
    parameters.  Returns a :class:`gfbjax.cont.NewtonSolution` (``x`` the state).
    """
    f = lambda s: balanced_vector_field(s, omega, params)  # noqa: E731

    def linearise(s):
        r = f(s)
        lu = jax.scipy.linalg.lu_factor(jax.jacfwd(f)(s))
        return jnp.max(jnp.abs(r)), jax.scipy.linalg.lu_solve(lu, -r), lu

    def trial(s, ds, t, lu):
        s1 = s + t * ds
        r1 = f(s1)
        ok = jnp.all(jnp.isfinite(r1)) & (_h_min(s1, params) > 0.0)
        return jnp.where(ok, jnp.linalg.norm(jax.scipy.linalg.lu_solve(lu, -r1)), jnp.inf)

    def damping(s, ds, lu):
        n_bar = jax.vmap(trial, in_axes=(None, None, 0, None))(s, ds, _STEP_FRACTIONS, lu)
        good = n_bar <= (1.0 - 0.25 * _STEP_FRACTIONS) * jnp.linalg.norm(ds)
        idx = jnp.where(jnp.any(good), jnp.argmax(good), len(_STEP_FRACTIONS) - 1)
        return jnp.where(jnp.isfinite(n_bar[idx]), _STEP_FRACTIONS[idx], 0.0)

    return cont.newton_solve(linearise, s0, _newton_settings(xtol, max_iter), damping=damping)


@dataclass
class StaticResult:
    """A static equilibrium of the balanced system at one speed and load (dimensionless unless stated).

    Attributes:
        omega: speed Omega_bar.
        w: extra specific load ``W/(p0 L D)`` per bearing.
        outcome: :class:`gfbjax.cont.Outcome` (a str enum): ``CONVERGED``, ``CONTACT`` (no equilibrium with an
            open film: the journal would touch the foil before carrying the load) or ``NO_SOLUTION``.
        message: a sentence on the outcome.
        load_fraction: fraction of the (gravity + extra) load carried by the last converged state (1 if converged).
        state: core state vector of the last converged equilibrium.
        x_j, y_j: journal centre over clearance c (y up).
        eccentricity: ``sqrt(x_j^2 + y_j^2)``.
        attitude_deg: angle from the load line (straight down) to the journal's displacement, in the direction of
            rotation [deg].
        h_min: minimum film thickness over c.
        theta: circumferential nodes [rad], foil ends included.
        z: axial nodes over L (edge 0 .. mid-plane 1/2; with ``axial_domain="full"`` edge to edge, 0 .. 1).
        pressure: p/p0 on all nodes, shape (len(theta), len(z)).
        foil: strip deflection q/c at the nodes (0 at the clamped ends).
        eigenvalues: eigenvalues of the Jacobian (per unit tau), sorted by decreasing real part.
        residual: max-norm of f at the solution; iterations: Newton iterations in total.
    """

    omega: float
    w: float
    outcome: str
    message: str
    load_fraction: float
    state: np.ndarray
    x_j: float
    y_j: float
    eccentricity: float
    attitude_deg: float
    h_min: float
    theta: np.ndarray
    z: np.ndarray
    pressure: np.ndarray
    foil: np.ndarray
    eigenvalues: np.ndarray
    residual: float
    iterations: int

    @property
    def converged(self) -> bool:
        return self.outcome == Outcome.CONVERGED

    @property
    def critical_eigenvalue(self) -> complex:
        """Eigenvalue with the largest real part."""
        return complex(self.eigenvalues[0]) if self.eigenvalues.size else complex("nan")

    @property
    def stable(self) -> bool | None:
        """Linearly stable: every eigenvalue of the Jacobian has a negative real part.  None when the solve did
        not converge (the state is no equilibrium, and its eigenvalues say nothing about stability)."""
        if not self.converged:
            return None
        return bool(self.eigenvalues.size) and float(self.eigenvalues[0].real) < 0.0

    def midplane_pressure(self) -> np.ndarray:
        """p/p0 along theta at the bearing's mid-plane."""
        return self.pressure[:, -1]

    def summary(self, spec: SystemSpec | None = None) -> dict[str, Any]:
        """JSON-ready summary; with ``spec`` also SI values (um, N, rpm, Hz)."""
        lam = self.critical_eigenvalue
        d: dict[str, Any] = {
            "omega_bar": self.omega, "w_specific": self.w, "outcome": self.outcome, "message": self.message,
            "load_fraction": self.load_fraction, "x_j": self.x_j, "y_j": self.y_j,
            "eccentricity": self.eccentricity, "attitude_deg": self.attitude_deg, "h_min": self.h_min,
            "p_max": float(self.pressure.max()), "q_max": float(self.foil.max()),
            "critical_eigenvalue": [lam.real, lam.imag], "stable": self.stable,
            "residual": self.residual, "iterations": self.iterations, "n_states": int(self.state.size),
        }
        if spec is not None:
            c_um = spec.c * 1e6
            d["SI"] = {
                "speed_rpm": spec.rpm(self.omega),
                "extra_load_N": self.w * spec.p0 * spec.L * 2 * spec.R,
                "total_load_N": spec.bearing_weight + self.w * spec.p0 * spec.L * 2 * spec.R,
                "x_j_um": self.x_j * c_um, "y_j_um": self.y_j * c_um, "h_min_um": self.h_min * c_um,
                "p_max_Pa": float(self.pressure.max()) * spec.p0,
                "critical_eigenvalue_per_s": [lam.real / spec.t_star, lam.imag / spec.t_star],
                "critical_frequency_Hz": abs(lam.imag) / spec.t_star / (2 * math.pi),
            }
        return d


def _check_inputs(params: Params, omega: Any, w: Any, guess_w: Any = None) -> tuple[float, float, float | None]:
    """Check the system (:meth:`Params.check`), the speed (:data:`gfbjax.limits.SPEED`) and the loads
    (:data:`gfbjax.limits.LOAD_W`) before any solve; returns the speed and loads as Python floats (NumPy and
    concrete JAX scalars are accepted)."""
    check_params(params)
    omega = limits.SPEED.check(omega, "omega")
    w = limits.LOAD_W.check(w, "w")
    if guess_w is not None:
        guess_w = limits.LOAD_W.check(guess_w, "guess_w")
    return omega, w, guess_w


def _build_result(s: Array, omega: float, w: float, params: Params, outcome: str, message: str,
                  fraction: float, residual: float, iterations: int) -> StaticResult:
    lay = layout(params)
    grid = lay.grid
    s_np = np.asarray(s)
    J = np.asarray(_jacobian(s, jnp.asarray(float(omega)), params))
    ev = np.linalg.eigvals(J)
    ev = ev[np.argsort(-ev.real)]
    xj, yj = (float(v) for v in np.asarray(lay.journal(s)))
    h = np.asarray(film(s, params))
    pressure = np.asarray(grid.full_field(lay.pressures(s)))
    foil = np.pad(np.asarray(lay.foil_deflection(s)), 1)
    z = np.asarray(grid.z_nodes())
    attitude = math.degrees(math.atan2(yj, xj) + math.pi / 2)
    attitude = (attitude + 180.0) % 360.0 - 180.0
    return StaticResult(
        omega=float(omega), w=float(w), outcome=outcome, message=message, load_fraction=float(fraction),
        state=s_np, x_j=xj, y_j=yj, eccentricity=math.hypot(xj, yj), attitude_deg=attitude,
        h_min=float(h.min()), theta=np.asarray(grid.theta_nodes(params.theta0)), z=z, pressure=pressure,
        foil=foil, eigenvalues=ev, residual=float(residual), iterations=int(iterations))


def _ramp(s: Array, params_at: Callable[[float], Params], omega: Array, xtol: float, min_step: float,
          first_step: float) -> tuple[Array, float, float, int]:
    """Follow equilibria from ``params_at(0)`` (solved by ``s``) to ``params_at(1)`` with an adaptive step and a
    secant predictor.  Returns the last converged state, the fraction reached, its residual and the iterations."""
    t, dt = 0.0, first_step
    s_prev, t_prev = None, 0.0
    res_norm, iters = 0.0, 0
    while t < 1.0 and dt >= min_step:
        target = min(1.0, t + dt)
        guess = s
        if s_prev is not None:  # secant predictor along the load path
            cand = s + (s - s_prev) * ((target - t) / (t - t_prev))
            if float(_h_min(cand, params_at(target))) > 0.0:
                guess = cand
        res = newton_solve(guess, omega, params_at(target), xtol=xtol)
        iters += int(res.iterations)
        if res.converged:
            s_prev, t_prev = s, t
            s, t, res_norm = res.x, target, float(res.residual)
            dt = 2.0 * dt
        else:
            dt *= 0.5
    return s, t, res_norm, iters


def solve_equilibrium(params: Params, omega: float, w: float = 0.0, *, guess: Array | None = None,
                      guess_w: float | None = None, xtol: float = 1e-10, min_fraction_step: float = 1e-4,
                      contact_h: float = 0.05) -> StaticResult:
    """Static equilibrium of the balanced system at speed ``omega`` under gravity plus the specific load ``w``.

    Args:
        params: dimensionless system (``SystemSpec.nondim()``).
        omega: speed Omega_bar in (0, 50] (:data:`gfbjax.limits.SPEED`).
        w: extra vertical specific load per bearing ``W/(p0 L D)`` in [0, 20], beyond gravity and beyond the
            system's own load (``SystemSpec.load``, carried in ``params.w_ext``); ``StaticResult.w`` is the total
            extra specific load, both together.
        guess: a core state to start from, e.g. the equilibrium at a nearby speed, or at the load ``guess_w``.
        guess_w: the load at which ``guess`` is an equilibrium; the load is then ramped from ``guess_w`` to ``w``.
            Without ``guess``, or when the warm start fails, the load is ramped from zero from the centred,
            ambient state (a homotopy in gravity + load with an adaptive step).
        xtol: Newton step tolerance (infinity norm, dimensionless states).
        min_fraction_step: smallest load-fraction increment before the ramp gives up.
        contact_h: when the ramp gives up with ``h_min`` below this, the outcome is ``"contact"``.

    Returns:
        A :class:`StaticResult`; never NaN: a film that closes before the load is carried gives
        ``outcome == "contact"`` and the last converged (partially loaded) state.
    """
    omega, w, guess_w = _check_inputs(params, omega, w, guess_w)
    # the system's own extra load (SystemSpec.load, in params.w_ext = 2 w) comes on top of ``w``: the solve ramps
    # the total, so it is folded into w here and params.w_ext is set from it by with_load
    w_sys = float(params.w_ext) / 2.0
    w, guess_w = w + w_sys, (None if guess_w is None else guess_w + w_sys)
    params = params.traced()
    omega_a = jnp.asarray(float(omega))
    iters = 0
    if guess is not None:
        w0 = w if guess_w is None else guess_w
        # the same load at every fraction: one Newton attempt, no point in halving the ramp step
        min_step = 1.0 if w0 == w else min_fraction_step
        s, t, res_norm, it = _ramp(jnp.asarray(guess), lambda t: with_load(params, w0 + t * (w - w0)), omega_a,
                                   xtol, min_step, first_step=1.0)
        iters += it
        if t >= 1.0:
            return _build_result(s, omega, w, params, Outcome.CONVERGED, "converged from the given guess", 1.0,
                                 res_norm, iters)
    from ..model import initial_state

    s0 = initial_state(with_load(params, w, 0.0))
    s, frac, res_norm, it = _ramp(s0, lambda t: with_load(params, w, t), omega_a, xtol, min_fraction_step,
                                  first_step=0.25)
    iters += it
    if frac >= 1.0:
        return _build_result(s, omega, w, params, Outcome.CONVERGED, "converged by load ramp", 1.0, res_norm, iters)
    p_last = with_load(params, w, frac)
    h_last = float(_h_min(s, p_last))
    if h_last < contact_h:
        msg = (f"the film closes: h_min = {h_last:.3g} c at {100 * frac:.2f}% of the load; the bearing cannot "
               "carry the full load at this speed")
        outcome = Outcome.CONTACT
    else:
        msg = f"Newton failed beyond {100 * frac:.2f}% of the load (h_min = {h_last:.3g} c)"
        outcome = Outcome.NO_SOLUTION
    return _build_result(s, omega, w, p_last, outcome, msg, frac, res_norm, iters)


def load_displacement(params: Params, omega: float, loads: Sequence[float],
                      progress: Callable[[int, int], None] | None = None) -> list[StaticResult]:
    """Equilibria for increasing specific loads ``loads`` (paper Fig. 4/5), each warm-started from the previous.

    Stops at the first load the bearing cannot carry (its result, with ``outcome == "contact"``, is the last
    entry), so the finished part is always returned.
    """
    out: list[StaticResult] = []
    guess, w_prev = None, None
    for k, w in enumerate(loads):
        r = solve_equilibrium(params, omega, float(w), guess=guess, guess_w=w_prev)
        out.append(r)
        if progress is not None:
            progress(k + 1, len(loads))
        if not r.converged:
            break
        guess, w_prev = r.state, float(w)
    return out
